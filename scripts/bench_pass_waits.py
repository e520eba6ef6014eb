"""A frame waited for once, at its end, against a wait after each of its passes, side by side (JSON).

    python scripts/bench_pass_waits.py [--cases flythrough,still] [--frames N] [--modes full,impostor,auto]
                                       [--json out/bench_pass_waits.json]

The renderer's frame waits for the GPU once (`cloudcore.gl.pass_clock`): the GPU runs one pass while the CPU
issues the next.  Here two renderers take turns frame by frame (the first of each turn alternating), one as it
is and one whose passes each end with a glFinish, as every pass did before; each frame is timed on the wall
clock to its glFinish, read-back excluded.  Per case and mode: the mean frames, their ratio with its 95%
interval (`ratio_interval`), and the largest difference of the two pictures (linear RGB, every 15th frame),
which is 0 unless auto mode's cost fit, fed with other times, chose otherwise.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
from OpenGL import GL  # noqa: E402

from cloudcore.cli.bench_suite import built_cases  # noqa: E402  (the suite `lod`'s scenes, views and sizes)
from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.gl.pass_clock import PassClock  # noqa: E402
from cloudcore.measure.benchmark import machine, ratio_interval, write_report  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402

#: the unmeasured frames each renderer draws first: its shaders compiled, its buffers made
WARMUP_FRAMES = 5
#: every this many frames the two pictures are compared
COMPARED_EVERY = 15


class WaitAfterEachPass(PassClock):
    """The clock as it was: each pass ends with a glFinish, so the GPU idles while the CPU issues the next."""

    @contextmanager
    def timed(self, name: str):
        with super().timed(name):
            yield
            GL.glFinish()


def side_by_side(scene, views, size, warmup: int, mode: str) -> dict:
    renderers = {"one_wait": FrameRenderer(*size), "wait_each_pass": FrameRenderer(*size)}
    renderers["wait_each_pass"]._clock.close()
    renderers["wait_each_pass"]._clock = WaitAfterEachPass()
    settings = RenderSettings(mode=mode)
    times = {name: [] for name in renderers}
    largest_difference = 0.0
    try:
        for time_s, camera in [views[0]] * max(warmup, WARMUP_FRAMES):
            for renderer in renderers.values():
                renderer.render(scene, camera=camera, settings=settings, time_s=time_s, read_back=False)
        for index, (time_s, camera) in enumerate(views):
            turn = list(renderers.items())
            pictures = []
            for name, renderer in turn if index % 2 == 0 else turn[::-1]:
                started = time.perf_counter()
                renderer.render(scene, camera=camera, settings=settings, time_s=time_s, read_back=False)
                GL.glFinish()
                times[name].append(1e3 * (time.perf_counter() - started))
                if index % COMPARED_EVERY == 0:
                    pictures.append(renderer.context.read_linear_rgb())
            if pictures:
                largest_difference = max(largest_difference, float(np.abs(pictures[0] - pictures[1]).max()))
    finally:
        for renderer in renderers.values():
            renderer.close()
    ratio, low, high = ratio_interval(times["one_wait"], [times["wait_each_pass"]])
    return {
        "mode": mode,
        "frames": len(views),
        "one_wait_ms_mean": float(np.mean(times["one_wait"])),
        "wait_each_pass_ms_mean": float(np.mean(times["wait_each_pass"])),
        "one_wait_over_wait_each_pass": ratio,
        "ratio_low": low,
        "ratio_high": high,
        "largest_picture_difference": largest_difference,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="flythrough,still")
    parser.add_argument("--frames", type=int, default=120, help="the first frames of each case measured")
    parser.add_argument("--modes", default="full,impostor,auto")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows = []
    for name, scene, views, size, warmup in built_cases("lod", args.cases.split(",")):
        for mode in args.modes.split(","):
            row = {
                "case": name,
                "size": f"{size[0]}x{size[1]}",
                **side_by_side(scene, views[: args.frames], size, warmup, mode),
            }
            rows.append(row)
            print(
                f"{name} {mode:8s}: one wait {row['one_wait_ms_mean']:.2f} ms, a wait each pass"
                f" {row['wait_each_pass_ms_mean']:.2f}: x{row['one_wait_over_wait_each_pass']:.3f}"
                f" [{row['ratio_low']:.3f}, {row['ratio_high']:.3f}]",
                file=sys.stderr,
                flush=True,
            )
    write_report({"machine": machine(), "date": time.strftime("%Y-%m-%d"), "rows": rows}, args.json, summary=rows)


if __name__ == "__main__":
    main()
