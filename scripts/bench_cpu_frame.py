"""The CPU's part of a frame, what a machine with a GPU pays for it, measured without one (JSON).

    python scripts/bench_cpu_frame.py [--cases flythrough] [--frames N] [--modes full,impostor,auto]
                                      [--json out/bench_cpu_frame.json]

On a GPU whose passes take less than the CPU takes to plan and issue them, the CPU bounds the frame
(the H200's auto mode: docs/performance.md).  Mesa's no-op driver (`GALLIUM_NOOP=1`) validates every
call in Mesa's OpenGL front end, as any driver does, and then drops the draws, dispatches and copies,
so a frame costs only its CPU part: the plan, numpy, Python and the driver's calls.  That part is
timed here on the machine in front of you, GPU or not.

The driver reads every buffer and pixel back as zeros, so the frames are drawn the way that needs
no read-back before it draws: the GPU's order (`splat_order = "gpu"`, whose draws are indirect) and the
raster's compositing.  Auto mode prices its choices with the prior costs (`LLVMPIPE_COSTS`), not with
times measured here, where drawing costs nothing.  Each case is one process's run, the modes'
renderers taking turns frame by frame (as `cloudview bench --suite lod`); each mode reports its frames' CPU time
(`FrameStats.cpu_ms`) with its plan's part (everything before the passes) and the passes' issuing.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
os.environ["GALLIUM_NOOP"] = "1"  # read when the driver loads: before the first context
# the no-op driver runs its calls on a driver thread (Mesa's threaded context) by default, and there it crashed
# when a frame's passes are not waited for one by one: a glBufferSubData into a buffer the pass before still
# uses (auto mode, the 100th flythrough frame or so; never under gdb, never with the thread off)
os.environ["GALLIUM_THREAD"] = "0"
from OpenGL import GL  # noqa: E402

from cloudcore.cli.bench_suite import built_cases  # noqa: E402  (the suite `lod`'s scenes, views and sizes)
from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.lod.costs import LLVMPIPE_COSTS  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402
from cloudcore.runtime.collector import freeze_what_is_set_up  # noqa: E402

#: the unmeasured frames a renderer draws first: its shaders compiled, its buffers made
WARMUP_FRAMES = 5


def timed_modes(scene, views, size, warmup: int, modes) -> list[dict]:
    """One row per mode: its frames' CPU milliseconds, mean and 95th percentile, and their parts."""
    renderers = {mode: FrameRenderer(*size) for mode in modes}
    try:
        renderer = GL.glGetString(GL.GL_RENDERER).decode()
        if renderer != "NOOP":
            raise SystemExit(f"bench_cpu_frame: the driver is {renderer!r}, not Mesa's no-op one (GALLIUM_NOOP)")
        settings = {mode: RenderSettings(mode=mode, splat_order="gpu", compositing="raster") for mode in modes}
        parts = {mode: [] for mode in modes}
        for index, (time_s, camera) in enumerate([views[0]] * max(warmup, WARMUP_FRAMES) + list(views)):
            if index == max(warmup, WARMUP_FRAMES):
                freeze_what_is_set_up()
            for mode, renderer in renderers.items():
                _, stats = renderer.render(
                    scene, camera=camera, settings=settings[mode], time_s=time_s, read_back=False, costs=LLVMPIPE_COSTS
                )
                parts[mode].append((stats.cpu_ms, stats.plan_ms, stats.cpu_ms - stats.plan_ms, stats.frame_ms))
    finally:
        for renderer in renderers.values():
            renderer.close()
    rows = []
    for mode, frames in parts.items():
        frames = np.array(frames[max(warmup, WARMUP_FRAMES) :])
        rows.append(
            {
                "mode": mode,
                "frames": len(frames),
                "cpu_ms_mean": float(np.mean(frames[:, 0])),
                "cpu_ms_p95": float(np.percentile(frames[:, 0], 95)),
                "plan_ms_mean": float(np.mean(frames[:, 1])),
                "passes_cpu_ms_mean": float(np.mean(frames[:, 2])),
                "frame_ms_mean": float(np.mean(frames[:, 3])),
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="flythrough")
    parser.add_argument("--frames", type=int, help="the first frames of each case measured (default: all)")
    parser.add_argument("--modes", default="full,impostor,auto")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows = []
    for name, scene, views, size, warmup in built_cases("lod", args.cases.split(",")):
        views = views[: args.frames]
        for row in timed_modes(scene, views, size, warmup, args.modes.split(",")):
            rows.append({"case": name, "size": f"{size[0]}x{size[1]}", **row})
            print(
                f"{name} {row['mode']:8s}: CPU {row['cpu_ms_mean']:.2f} ms a frame (p95 {row['cpu_ms_p95']:.2f}),"
                f" plan {row['plan_ms_mean']:.2f}, passes {row['passes_cpu_ms_mean']:.2f}",
                file=sys.stderr,
                flush=True,
            )
    write_report({"machine": machine(), "date": time.strftime("%Y-%m-%d"), "rows": rows}, args.json, summary=rows)


if __name__ == "__main__":
    main()
