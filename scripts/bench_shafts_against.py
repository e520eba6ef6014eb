"""The light shafts' part of the world pass and the frame, this tree's against a revision's, side by side in turns.

    python scripts/bench_shafts_against.py --against main [--views evening,default] [--size 640x480]
        [--frames 40] [--warmup 5] [--json out/bench_shafts_against.json]

Two worker processes, this tree's `cloudcore` and the revision's (a temporary worktree on its PYTHONPATH), each
with two renderers, one drawing with the light shafts and one without (`RenderSettings().light_shafts`), draw
each view in auto mode (the prior costs, `LLVMPIPE_COSTS`: both draw the same plans), the four taking turns frame
by frame in the balanced order of `measure.benchmark.turns`, so that all see the same machine load.  Views: into
the 17:30 sun from the valley (`bench_light_shafts.toward_the_sun(17.5, 2600, 500, 0.12)`, where Yusov's cut
darkens the clouds in front of the sun) and the default view.  Per view, with the 95% intervals of
`measure.benchmark.ratio_interval`: each tree's world pass with the shafts over without (what the shafts cost it),
and this tree's world pass and frame with the shafts over the revision's
(docs/performance.md#the-light-shafts-cut-at-the-clouds).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from cloudcore.measure.benchmark import machine, ratio_interval, turns, write_report

#: the ways each view is drawn: (tree, shafts)
WAYS = (("this", True), ("this", False), ("against", True), ("against", False))


def worker(view: str, size: str) -> None:
    """Serve a parent over stdin/stdout: 'frame SHAFTS' (1 or 0) draws the view with or without the shafts and
    answers its `world_ms` and `frame_ms`; 'quit'."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    sys.path.insert(0, str(Path(__file__).resolve().parent))  # this tree's bench_light_shafts, for its view
    from bench_light_shafts import toward_the_sun

    from cloudcore.gl import FrameRenderer
    from cloudcore.lod.costs import LLVMPIPE_COSTS
    from cloudcore.model.settings import RenderSettings
    from cloudcore.resources import DEFAULT_SCENE
    from cloudcore.scenes.files import load_scene

    scene = load_scene(DEFAULT_SCENE)
    hours, camera = (17.5, toward_the_sun(17.5, 2600.0, 500.0, 0.12)) if view == "evening" else (None, None)
    width, height = (int(n) for n in size.split("x"))
    renderers = {shafts: FrameRenderer(width, height) for shafts in (True, False)}
    print("ready", flush=True)
    for line in sys.stdin:
        words = line.split()
        if words[0] == "quit":
            break
        shafts = words[1] == "1"
        _, stats = renderers[shafts].render(
            scene,
            time_of_day=hours,
            camera=camera,
            settings=RenderSettings(light_shafts=shafts),
            costs=LLVMPIPE_COSTS,
            read_back=False,
        )
        print(stats.world_ms, stats.frame_ms, flush=True)
    for renderer in renderers.values():
        renderer.close()


def compare(trees: dict, view: str, size: str, frames: int, warmup: int) -> dict:
    """The row of `view`: the four ways' world passes and frames in turns, their ratios."""
    # here, not at the top: the revision's worker runs this file over its own `cloudcore`, which may not have it
    from cloudcore.measure.benchmark import tree_workers

    workers = tree_workers([sys.executable, str(Path(__file__).resolve()), "--view", view, "--size", size], trees)
    for process in workers.values():
        process.stdout.readline()
    world, frame = ({way: [] for way in WAYS} for _ in range(2))
    for index, order in enumerate(turns(len(WAYS), warmup + frames)):
        for tree, shafts in (WAYS[run] for run in order):
            workers[tree].stdin.write(f"frame {int(shafts)}\n")
            workers[tree].stdin.flush()
            world_ms, frame_ms = (float(value) for value in workers[tree].stdout.readline().split())
            if index >= warmup:
                world[tree, shafts].append(world_ms)
                frame[tree, shafts].append(frame_ms)
    for process in workers.values():
        process.stdin.write("quit\n")
        process.stdin.flush()
        process.wait()

    def interval(numerator, denominator) -> list[float]:
        return list(ratio_interval(numerator, [denominator]))

    return {
        "view": view,
        "size": size,
        "frames": frames,
        "world_ms_median": {
            f"{tree}_{'shafts' if s else 'none'}": float(np.median(world[tree, s])) for tree, s in WAYS
        },
        "frame_ms_median": {
            f"{tree}_{'shafts' if s else 'none'}": float(np.median(frame[tree, s])) for tree, s in WAYS
        },
        "this_world_shafts_over_none_95": interval(world["this", True], world["this", False]),
        "against_world_shafts_over_none_95": interval(world["against", True], world["against", False]),
        "world_this_over_against_95": interval(world["this", True], world["against", True]),
        "frame_this_over_against_95": interval(frame["this", True], frame["against", True]),
        "world_this_over_against_no_shafts_95": interval(world["this", False], world["against", False]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="main", help="the git revision this tree's shafts are set against")
    parser.add_argument("--views", default="evening,default")
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--frames", type=int, default=40, help="frames of each way timed")
    parser.add_argument("--warmup", type=int, default=5, help="frames of each way not timed")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--view", help=argparse.SUPPRESS)
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)  # its tree: the process's PYTHONPATH
    args = parser.parse_args()
    if args.worker:
        return worker(args.view, args.size)
    from cloudcore.measure.benchmark import revision_trees

    here = Path(__file__).resolve().parents[1]
    with revision_trees({"against": args.against}, here) as against:
        trees = {"this": here, "against": against["against"]}
        rows = [compare(trees, view, args.size, args.frames, args.warmup) for view in args.views.split(",")]
    write_report({"machine": machine(), "against": args.against, "rows": rows}, args.json)


if __name__ == "__main__":
    main()
