"""The world pass's time, this tree's against other revisions', side by side in one run, and each picture's error.

    python scripts/bench_world_cost.py [--sizes 640x480,880x680,1280x800] [--rounds 12]
        [--against uncut=aerial --against main_gradient=main --against plain=2d46b6e^1]
        [--ways patch,relief_and_reach,relief_and_reach_finer] [--path SCENE:PATH:FRAMES] [--parts]
        [--json out/bench_world_cost.json]
    python scripts/bench_world_cost.py --sizes 880x680 --ways relief_and_reach --against base=c334bbb --parts
    python scripts/bench_world_cost.py --sizes 640x360 --ways relief_and_reach --against base=c334bbb --parts \
        --path cumulus_field.toml:flight:40

Each way is a worker process drawing the default view in auto mode (`RenderSettings()`) through its own
revision's `cloudcore` (a temporary worktree on its PYTHONPATH): this tree on the patch of the revisions
before it (the default scene without `relief` and `reach`: `patch`), this tree on its default scene (the valley's
mountains and the ground to 40 km: `relief_and_reach`), the same with tiles split four times as far (nearly the
uncut terrain: `relief_and_reach_finer`), which of these `--ways` names, and each `--against` revision on its own
default scene (a NAME ending in `_gradient`: under the gradient sky without aerial perspective, the plain world
pass of a revision with the atmosphere).  With `--path`, every way draws a scene file's camera path instead (a
file under cloudcore/resources/scenes/ by its name, or a path; `FRAMES` views along it, drawn in turn and again
from the first).  The workers take turns, a few frames each, round after round, so that all see the same machine
load; the medians of `FrameStats.world_ms` after the warm-up are reported, the mean of `relief_and_reach`'s over
each `--against` way's with its 95% interval (`measure.benchmark.ratio_interval`, the frames of one turn paired),
and the PSNR of each picture against the one it cuts (`cloudview compare`'s), and of `relief_and_reach`'s against
each `--against` way's.  With `--parts`, each part of the world pass is also timed between two `glFinish` (so
the pass is slower for it), ms a frame, medians: the light shafts' march with the terrain's and the clouds' depth
drawn for it, the sky's picture, the terrain, the sky's read; and each part's mean ratio with its interval as the
pass's.
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


#: (the class, its function, the part's name): the parts of the world pass `--parts` times, in each tree
PARTS = (
    ("world.WorldPass", "draw", "world pass"),
    ("light_shafts.LightShaftPass", "march", "light shafts (with both depths)"),
    ("world.TerrainMesh", "draw_depth", "light shafts: the terrain's depth"),
    ("frame.FrameRenderer", "_cloud_depth_drawer", "light shafts: the clouds' depth"),
    ("world.WorldPass", "_draw_sky_picture", "the sky's picture"),
    ("world.TerrainMesh", "draw", "the terrain"),
    ("world.WorldPass", "_draw_sky", "the sky's read"),
)


def timed_parts() -> dict[str, list[float]]:
    """Time each of `PARTS` between two `glFinish` from now on; the times (ms) by part, filled as frames draw."""
    import time

    from OpenGL import GL

    from cloudcore.gl import frame, light_shafts, world

    modules = {"frame": frame, "light_shafts": light_shafts, "world": world}
    spent: dict[str, list[float]] = {}

    def timed(function, name: str):
        def part(*args, **kwargs):
            GL.glFinish()
            start = time.perf_counter()
            result = function(*args, **kwargs)
            GL.glFinish()
            spent.setdefault(name, []).append(1e3 * (time.perf_counter() - start))
            return result

        return part

    for owner_name, attribute, name in PARTS:
        module, _, owner = owner_name.partition(".")
        owner = getattr(modules[module], owner)
        function = getattr(owner, attribute)
        if attribute == "_cloud_depth_drawer":  # a maker of the drawer: the drawer it makes is timed
            setattr(owner, attribute, lambda *args, made=function, name=name: timed(made(*args), name))
        else:
            setattr(owner, attribute, timed(function, name))
    return spent


def worker(size: str, strip_reach: bool, finer: bool, gradient: bool, path: str | None, parts: bool) -> None:
    """Serve a parent over stdin/stdout: 'frames N' draws N frames and answers their world_ms (and with `parts`
    each part's times); 'image PATH' draws one and saves it; 'quit'."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import dataclasses
    import itertools

    from cloudcore.gl.frame import FrameRenderer
    from cloudcore.measure.benchmark import path_views, still_views
    from cloudcore.model.settings import RenderSettings
    from cloudcore.resources import DEFAULT_SCENE, resource_path
    from cloudcore.scenes.files import load_scene

    if path is None:
        scene = load_scene(DEFAULT_SCENE)
        views = still_views(scene, 1)
    else:
        file, name, count = path.split(":")
        scene = load_scene(file if Path(file).exists() else resource_path("scenes", file))
        views = path_views(scene, name, int(count))
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
    spent = timed_parts() if parts else {}
    width, height = (int(v) for v in size.split("x"))
    next_view = itertools.cycle(views).__next__
    with FrameRenderer(width, height) as renderer:

        def draw(read_back: bool):
            time_s, camera = next_view()
            return renderer.render(scene, camera=camera, time_s=time_s, settings=settings, read_back=read_back)

        for line in sys.stdin:
            command, _, argument = line.strip().partition(" ")
            if command == "frames":
                spent.clear()
                times = [draw(False)[1].world_ms for _ in range(int(argument))]
                print(json.dumps({"world_ms": times, "parts": spent}), flush=True)
            elif command == "image":
                image, _ = draw(True)
                np.save(argument, image)
                print("{}", flush=True)
            else:
                return


class Way:
    """One worker: a revision's tree (None: this one) and how it draws."""

    def __init__(self, name: str, tree: Path, size: str, drawn: list[str], *, strip_reach=False, finer=False):
        """`drawn`: the worker's arguments for what every way draws (`--path`, `--parts`)."""
        self.name = name
        command = [sys.executable, __file__, "--worker", size, *drawn]
        command += ["--strip-reach"] * strip_reach + ["--finer"] * finer + ["--gradient"] * name.endswith("_gradient")
        env = {**os.environ, "PYTHONPATH": str(tree), "PYOPENGL_PLATFORM": "egl"}
        self.process = subprocess.Popen(command, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.times: list[float] = []
        self.parts: dict[str, list[float]] = {}

    def ask(self, line: str) -> dict:
        self.process.stdin.write(line + "\n")
        self.process.stdin.flush()
        return json.loads(self.process.stdout.readline())

    def close(self) -> None:
        self.process.stdin.write("quit\n")
        self.process.stdin.close()
        self.process.wait()


#: this tree's ways (`--ways`): (name, its terrain without relief and reach, its tiles split farther)
THIS_TREE_WAYS = {
    "patch": (True, False),
    "relief_and_reach": (False, False),
    "relief_and_reach_finer": (False, True),
}


def measure(
    size: str, trees: dict[str, Path], here: Path, rounds: int, folder: Path, ways: list[str], drawn: list[str]
) -> dict:
    ways = [
        *(
            Way(name, here, size, drawn, strip_reach=THIS_TREE_WAYS[name][0], finer=THIS_TREE_WAYS[name][1])
            for name in ways
        ),
        *(Way(name, tree, size, drawn) for name, tree in trees.items()),
    ]
    try:
        for way in ways:
            way.ask(f"frames {WARM_UP}")
        for _ in range(rounds):
            for way in ways:
                answer = way.ask(f"frames {PER_TURN}")
                way.times += answer["world_ms"]
                for part, times in answer["parts"].items():
                    way.parts.setdefault(part, []).extend(times)
        images = {}
        for way in ways:
            path = folder / f"{way.name}_{size}.npy"
            way.ask(f"image {path}")
            images[way.name] = np.load(path)
    finally:
        for way in ways:
            way.close()
    from cloudcore.measure.benchmark import ratio_interval
    from cloudcore.measure.imagecompare import compare

    row = {"size": size, **{f"{way.name}_world_ms": float(np.median(way.times)) for way in ways}}
    for way in ways:
        if way.parts:
            row[f"{way.name}_parts_ms"] = {part: float(np.median(times)) for part, times in way.parts.items()}
    # each cut against the picture it cuts: the patch against the uncut revision's, the tiles against finer ones,
    # this tree against each revision
    pairs = [("patch", "uncut"), ("relief_and_reach", "relief_and_reach_finer")]
    pairs += [("relief_and_reach", name) for name in trees]
    for cut, uncut in pairs:
        if cut in images and uncut in images:
            row[f"{cut}_psnr_db_against_{uncut}"] = compare(images[cut], images[uncut]).psnr_db
    this = next((way for way in ways if way.name == "relief_and_reach"), None)
    for way in ways:
        if this is not None and way.name in trees:
            ratio, low, high = ratio_interval(this.times, [way.times])
            row[f"relief_and_reach_world_over_{way.name}"] = [ratio, low, high]
            # each part's ratio too, where both drew it once a frame (the part a change cuts, out of the pass's noise)
            row[f"relief_and_reach_parts_over_{way.name}"] = {
                part: list(ratio_interval(times, [way.parts[part]]))
                for part, times in this.parts.items()
                if len(way.parts.get(part, ())) == len(times) == len(this.times)
            }
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="640x480,880x680,1280x800")
    parser.add_argument("--rounds", type=int, default=12)
    parser.add_argument("--against", action="append", default=[], help="NAME=REV: a revision's world pass beside")
    parser.add_argument(
        "--ways", default=",".join(THIS_TREE_WAYS), help="this tree's ways, of " + ", ".join(THIS_TREE_WAYS)
    )
    parser.add_argument(
        "--path", help="SCENE:PATH:FRAMES: views along a scene file's camera path, not the default view"
    )
    parser.add_argument("--parts", action="store_true", help="each part of the world pass timed too")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--gradient", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--strip-reach", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--finer", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.strip_reach, args.finer, args.gradient, args.path, args.parts)
        return
    here = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(here))
    from cloudcore.measure.benchmark import machine, revision_trees, write_report

    revisions = dict(against.partition("=")[::2] for against in args.against)
    with tempfile.TemporaryDirectory() as folder, revision_trees(revisions, here) as trees:
        drawn = (["--path", args.path] if args.path else []) + ["--parts"] * args.parts
        ways = args.ways.split(",")
        rows = [measure(size, trees, here, args.rounds, Path(folder), ways, drawn) for size in args.sizes.split(",")]
    write_report(
        {
            "machine": machine(),
            "load_average": os.getloadavg(),
            "against": args.against,
            "path": args.path,
            "sizes": rows,
        },
        args.json,
    )


if __name__ == "__main__":
    main()
