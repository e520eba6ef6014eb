"""The whole frame of this tree against a revision's, side by side: a change meant to keep frames and pictures.

    python scripts/bench_frame_against.py --against main [--cases flythrough,field] [--every 10]
        [--modes auto,full] [--warmup 5] [--json out/bench_frame_against.json]
    python scripts/bench_frame_against.py --against main --cases cumulus_field.toml:flight:50 --modes auto,full

A case `SCENE:PATH:FRAMES` is a scene file's camera path (a file under cloudcore/resources/scenes/ by its name, or a
path), `FRAMES` views spread along it, at 640x360 (the cumulus field demo's `cloudview bench` row of issue 51).

Two worker processes, this tree's `cloudcore` and the revision's (a temporary worktree on its PYTHONPATH), draw
the same views of each case of the suite `lod` (`cloudcore/resources/bench/lod.toml`, every `--every`th view), in
each mode, taking turns frame by frame in the balanced order of `measure.benchmark.turns`, so that both see the
same machine load.  Auto mode prices its choices with the prior costs (`LLVMPIPE_COSTS`), not with times
measured in each process, so both draw the same plans.  Reports per case and mode the ratio of this tree's mean
`frame_ms` over the revision's after the warm-up with its 95% interval (`measure.benchmark.ratio_interval`), and
the PSNR of every fifth picture of this tree against the revision's (infinite: the same bytes).  The revision
must have the suite (`cloudcore.cli.bench_suite`).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from cloudcore.measure.benchmark import machine, ratio_interval, turns, write_report
from cloudcore.measure.imagecompare import compare as compare_images

#: one picture of this many frames is compared
PICTURE_EVERY = 5


def worker(case: str, every: int, modes: list[str]) -> None:
    """Serve a parent over stdin/stdout: 'frame MODE I [PATH]' draws view I in MODE (saving its picture to PATH)
    and answers its `frame_ms`; the first line answered is the number of views; 'quit'."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from cloudcore.cli.bench_suite import built_cases
    from cloudcore.gl import FrameRenderer
    from cloudcore.lod.costs import LLVMPIPE_COSTS
    from cloudcore.model.settings import RenderSettings

    if case.count(":") == 2:
        scene, views, size = path_case(case)
    else:
        _, scene, views, size, _ = built_cases("lod", [case])[0]
    views = views[::every]
    renderers = {mode: FrameRenderer(*size) for mode in modes}
    print(len(views), flush=True)
    for line in sys.stdin:
        words = line.split()
        if words[0] == "quit":
            break
        mode, index = words[1], int(words[2])
        time_s, camera = views[index]
        image, stats = renderers[mode].render(
            scene, camera=camera, time_s=time_s, settings=RenderSettings(mode=mode), costs=LLVMPIPE_COSTS
        )
        if len(words) > 3:
            np.save(words[3], image)
        print(stats.frame_ms, flush=True)
    for renderer in renderers.values():
        renderer.close()


def path_case(case: str) -> tuple:
    """(scene, views, size) of a case `SCENE:PATH:FRAMES`: `FRAMES` views along the scene's camera path `PATH`."""
    from cloudcore.measure.benchmark import path_views
    from cloudcore.resources import resource_path
    from cloudcore.scenes.files import load_scene

    file, path, frames = case.split(":")
    scene = load_scene(file if Path(file).exists() else resource_path("scenes", file))
    return scene, path_views(scene, path, int(frames)), (640, 360)


def compare(trees: dict, case: str, every: int, modes: list[str], warmup: int, folder: Path) -> list[dict]:
    """One row per mode of `case`: this tree's frames against the revision's, and their pictures' PSNR."""
    # here, not at the top: the revision's worker runs this file over its own `cloudcore`, which may not have it
    from cloudcore.measure.benchmark import tree_workers

    command = [
        sys.executable,
        str(Path(__file__).resolve()),
        "--case",
        case,
        "--every",
        str(every),
        "--modes",
        ",".join(modes),
    ]
    workers = tree_workers(command, trees)
    views = [int(process.stdout.readline()) for process in workers.values()][0]

    def ask(name: str, line: str) -> float:
        workers[name].stdin.write(line + "\n")
        workers[name].stdin.flush()
        return float(workers[name].stdout.readline())

    names = list(trees)
    rows = []
    for mode in modes:
        times, psnrs = {name: [] for name in names}, []
        for index, order in enumerate(turns(len(names), views)):
            pictures = {name: folder / f"{name}_{mode}_{index}.npy" for name in names}
            picture = index % PICTURE_EVERY == 0
            for name in (names[run] for run in order):
                ms = ask(name, f"frame {mode} {index}" + (f" {pictures[name]}" if picture else ""))
                if index >= warmup:
                    times[name].append(ms)
            if picture:
                psnrs.append(compare_images(*(np.load(pictures[name]) for name in names)).psnr_db)
        ratio, low, high = ratio_interval(times["this"], [times["against"]])
        rows.append(
            {
                "case": case,
                "mode": mode,
                "frames": len(times["this"]),
                "this_frame_ms_mean": float(np.mean(times["this"])),
                "against_frame_ms_mean": float(np.mean(times["against"])),
                "ratio": ratio,
                "ratio_95": [low, high],
                "psnr_db_worst": float(min(psnrs)),
                "pictures": len(psnrs),
            }
        )
    for process in workers.values():
        process.stdin.write("quit\n")
        process.stdin.flush()
        process.wait()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="main", help="the git revision whose frames this tree's are set against")
    parser.add_argument("--cases", default="flythrough")
    parser.add_argument("--every", type=int, default=10, help="draw every Nth view of a case")
    parser.add_argument("--modes", default="auto,full")
    parser.add_argument("--warmup", type=int, default=5, help="frames of each mode not timed")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--case", help=argparse.SUPPRESS)
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)  # its tree: the process's PYTHONPATH
    args = parser.parse_args()
    modes = args.modes.split(",")
    if args.worker:
        return worker(args.case, args.every, modes)
    # here, not at the top: the revision's worker runs this file over its own `cloudcore`, which may not have it
    from cloudcore.measure.benchmark import revision_trees

    here = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory() as folder, revision_trees({"against": args.against}, here) as against:
        trees = {"this": here, "against": against["against"]}
        rows = [
            row
            for case in args.cases.split(",")
            for row in compare(trees, case, args.every, modes, args.warmup, Path(folder))
        ]
    write_report({"machine": machine(), "against": args.against, "rows": rows}, args.json)


if __name__ == "__main__":
    main()
