"""The world pass's time, this tree's against other revisions', side by side in one run, and each picture's error.

    python scripts/bench_world_cost.py [--sizes 640x480,880x680,1280x800] [--rounds 12]
        [--against uncut=aerial --against main_gradient=main --against plain=2d46b6e^1]
        [--json out/bench_world_cost.json]

Each way is a worker process drawing the default view in auto mode (`RenderSettings()`) through its own
revision's `cloudcore` (a temporary worktree on its PYTHONPATH): this tree on the patch of the revisions
before it (the default scene without `relief` and `reach`), this tree on its default scene (the valley's
mountains and the ground to 40 km), the same with tiles split four times as far (nearly the uncut terrain),
and each `--against` revision on its own default scene (a NAME ending in `_gradient`: under the gradient sky
without aerial perspective, the plain world pass of a revision with the atmosphere).  The workers take turns,
a few frames each, round after round, so that all see the same machine load; the medians of
`FrameStats.world_ms` after the warm-up are reported, and the PSNR of each picture against the one it cuts
(`cloudview compare`'s).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

#: frames drawn before timing (impostors made, tiles meshed) and in each turn
WARM_UP, PER_TURN = 6, 3
#: the tiles' split distance of the nearly uncut terrain, in `terrain_tiles.SPLIT_DISTANCE`s
FINER = 4.0


def worker(size: str, strip_reach: bool, finer: bool, gradient: bool) -> None:
    """Serve a parent over stdin/stdout: 'frames N' draws N frames and answers their world_ms; 'image PATH' draws
    one and saves it; 'quit'."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import dataclasses

    from cloudcore.gl.frame import FrameRenderer
    from cloudcore.model.settings import RenderSettings
    from cloudcore.resources import DEFAULT_SCENE
    from cloudcore.scenes.files import load_scene

    scene = load_scene(DEFAULT_SCENE)
    if strip_reach:
        scene = dataclasses.replace(scene, terrain=dataclasses.replace(scene.terrain, relief=0.0, reach=0.0))
    settings = RenderSettings()
    if gradient:  # the plain world pass of a revision with the atmosphere: the gradient, no air
        from cloudcore.model.scene import Air

        scene = dataclasses.replace(scene, lighting=dataclasses.replace(scene.lighting, air=Air(sky="gradient")))
        if "aerial_perspective" in {field.name for field in dataclasses.fields(settings)}:
            settings = dataclasses.replace(settings, aerial_perspective=False)
    if finer:
        from cloudcore.world import terrain_tiles

        terrain_tiles.SPLIT_DISTANCE *= FINER
    width, height = (int(v) for v in size.split("x"))
    with FrameRenderer(width, height) as renderer:
        for line in sys.stdin:
            command, _, argument = line.strip().partition(" ")
            if command == "frames":
                times = [
                    renderer.render(scene, settings=settings, read_back=False)[1].world_ms for _ in range(int(argument))
                ]
                print(json.dumps(times), flush=True)
            elif command == "image":
                image, _ = renderer.render(scene, settings=settings)
                np.save(argument, image)
                print("[]", flush=True)
            else:
                return


class Way:
    """One worker: a revision's tree (None: this one) and how it draws."""

    def __init__(self, name: str, tree: Path, size: str, *, strip_reach=False, finer=False):
        self.name = name
        command = [sys.executable, __file__, "--worker", size]
        command += ["--strip-reach"] * strip_reach + ["--finer"] * finer + ["--gradient"] * name.endswith("_gradient")
        env = {**os.environ, "PYTHONPATH": str(tree), "PYOPENGL_PLATFORM": "egl"}
        self.process = subprocess.Popen(command, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.times: list[float] = []

    def ask(self, line: str) -> list:
        self.process.stdin.write(line + "\n")
        self.process.stdin.flush()
        return json.loads(self.process.stdout.readline())

    def close(self) -> None:
        self.process.stdin.write("quit\n")
        self.process.stdin.close()
        self.process.wait()


def measure(size: str, trees: dict[str, Path], here: Path, rounds: int, folder: Path) -> dict:
    ways = [
        Way("patch", here, size, strip_reach=True),
        Way("relief_and_reach", here, size),
        Way("relief_and_reach_finer", here, size, finer=True),
        *(Way(name, tree, size) for name, tree in trees.items()),
    ]
    try:
        for way in ways:
            way.ask(f"frames {WARM_UP}")
        for _ in range(rounds):
            for way in ways:
                way.times += way.ask(f"frames {PER_TURN}")
        images = {}
        for way in ways:
            path = folder / f"{way.name}_{size}.npy"
            way.ask(f"image {path}")
            images[way.name] = np.load(path)
    finally:
        for way in ways:
            way.close()
    from cloudcore.measure.imagecompare import compare

    row = {"size": size, **{f"{way.name}_world_ms": float(np.median(way.times)) for way in ways}}
    # each cut against the picture it cuts: the patch against the uncut revision's, the tiles against finer ones
    pairs = [("patch", "uncut"), ("relief_and_reach", "relief_and_reach_finer")]
    for cut, uncut in pairs:
        if uncut in images:
            row[f"{cut}_psnr_db_against_{uncut}"] = compare(images[cut], images[uncut]).psnr_db
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="640x480,880x680,1280x800")
    parser.add_argument("--rounds", type=int, default=12)
    parser.add_argument("--against", action="append", default=[], help="NAME=REV: a revision's world pass beside")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--gradient", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--strip-reach", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--finer", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.strip_reach, args.finer, args.gradient)
        return
    here = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(here))
    from cloudcore.measure.benchmark import machine, revision_trees, write_report

    revisions = dict(against.partition("=")[::2] for against in args.against)
    with tempfile.TemporaryDirectory() as folder, revision_trees(revisions, here) as trees:
        rows = [measure(size, trees, here, args.rounds, Path(folder)) for size in args.sizes.split(",")]
    write_report({"machine": machine(), "against": args.against, "sizes": rows}, args.json)


if __name__ == "__main__":
    main()
