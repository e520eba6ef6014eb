"""The frame planner's own time: `plan_frame` replayed alone on the inputs of real frames, per mode (JSON).

    python scripts/bench_plan.py [--cases flythrough] [--frames 300] [--against REV] [--json out/bench_plan.json]

Each case of `bench_lod.py` is rendered once per mode (full 3D, impostor mode, auto), and every call of
`plan_frame` keeps its inputs: the units, camera, settings, the state the frames before left, the objects
and the particles.  The frames after the case's warm-up are then planned again, alone, in passes taking
turns: a pass plans every frame once.  `--against REV` takes `cloudcore/lod/frameplan.py` of a git revision
beside the working tree's, on the same inputs, the two taking turns pass by pass (what a change to the
planner saves, without the noise of two runs; the other modules are the working tree's for both), and
counts the frames whose plans differ between the two in any field (`plans_differing`: 0 for a change
meant only to be faster).  Reports the median and the least of each way's passes, in ms a frame.  Nothing
is drawn while it times: on the GPU's machine the planner is what auto mode costs over impostor mode
(docs/performance.md).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
import types
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_lod import cases  # noqa: E402  (a sibling script: the same scenes, views and sizes)

import cloudcore.gl.frame as frame_module  # noqa: E402
from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.lod import frameplan  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.settings import RenderSettings  # noqa: E402

MODES = ("full", "impostor", "auto")
PASSES = 6


def captured_calls(scene, views, size, warmup: int, mode: str) -> list:
    """The (arguments, keywords) of every `plan_frame` call after `warmup` frames of `views` in `mode`."""
    calls = []

    def keeping(*arguments, **keywords):
        calls.append((arguments, keywords))
        return frameplan.plan_frame(*arguments, **keywords)

    frame_module.plan_frame = keeping
    try:
        with FrameRenderer(*size) as renderer:
            for time_s, camera in views:
                renderer.render(
                    scene, camera=camera, time_s=time_s, settings=RenderSettings(mode=mode), read_back=False
                )
    finally:
        frame_module.plan_frame = frameplan.plan_frame
    return calls[warmup:]


def planner_of(revision: str):
    """`plan_frame` of `cloudcore/lod/frameplan.py` at git `revision`, importing the working tree's other modules."""
    root = Path(__file__).resolve().parent.parent
    source = subprocess.run(
        ["git", "show", f"{revision}:cloudcore/lod/frameplan.py"], cwd=root, capture_output=True, text=True, check=True
    ).stdout
    module = types.ModuleType(f"cloudcore.lod.frameplan_at_{revision}")
    sys.modules[module.__name__] = module  # dataclasses look their module up by name
    exec(compile(source, f"frameplan.py at {revision}", "exec"), module.__dict__)
    return module.plan_frame


def timed_passes(planners: dict, calls: list) -> dict:
    """Per planner, its passes' ms a frame, the planners taking turns pass by pass (each first as often)."""
    times = {name: [] for name in planners}
    names = list(planners)
    for index in range(PASSES):
        for name in names if index % 2 == 0 else reversed(names):
            start = time.perf_counter()
            for arguments, keywords in calls:
                planners[name](*arguments, **keywords)
            times[name].append(1e3 * (time.perf_counter() - start) / len(calls))
    return times


def plans_differing(planners: dict, calls: list) -> int:
    """How many of `calls` the planners plan differently (their plans' reprs, every field, compared)."""
    first, *others = planners.values()
    differing = 0
    for arguments, keywords in calls:
        planned = repr(first(*arguments, **keywords))
        differing += any(repr(other(*arguments, **keywords)) != planned for other in others)
    return differing


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="flythrough")
    parser.add_argument("--frames", type=int, default=300, help="frames planned per case after its warm-up")
    parser.add_argument("--against", help="a git revision whose frameplan.py is timed beside the working tree's")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    planners = {"working tree": frameplan.plan_frame}
    if args.against:
        planners[args.against] = planner_of(args.against)
    rows = []
    for name, scene, views, size, warmup in cases(set(args.cases.split(",")), quick=False):
        views = views[: warmup + args.frames]
        for mode in MODES:
            calls = captured_calls(scene, views, size, warmup, mode)
            differing = plans_differing(planners, calls) if args.against else None
            for planner, times in timed_passes(planners, calls).items():
                row = {
                    "case": name,
                    "mode": mode,
                    "planner": planner,
                    "frames": len(calls),
                    "plan_ms_median": float(np.median(times)),
                    "plan_ms_least": float(np.min(times)),
                    "plans_differing": differing,
                }
                rows.append(row)
                print(
                    f"{name} {mode:8s} {planner}: {row['plan_ms_median']:.3f} ms a frame"
                    f" (least {row['plan_ms_least']:.3f})" + (f", {differing} plans differ" if args.against else ""),
                    file=sys.stderr,
                    flush=True,
                )
    write_report({"machine": machine(), "date": time.strftime("%Y-%m-%d"), "rows": rows}, args.json, summary=rows)


if __name__ == "__main__":
    main()
