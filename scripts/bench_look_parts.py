"""Where one look of the editor's dragged time-of-day slider goes: the worker's light pass, and each part of the
frame that draws the look, this tree's beside other revisions'.

    python scripts/bench_look_parts.py [--looks 8] [--rounds 2] [--size 879x683] [--against base=main]
                                       [--json out/bench_look_parts.json]

The editor's loop without its window: a renderer of the viewport's size with the editor's frame budget and air
(`LiveAir`); for each look, an hour 0.12 later than the one before (the GUI test's drag moves about that far a
look), the preview light pass of `IlluminationCache.missing` timed as the relighting worker runs it
(`cloudcore.light.relighting`), then the frame that draws the look.  Each part of that frame is timed between two
`glFinish`, so what the GPU does lands in the part that asked for it (the frame is slower for it).  Each way (this
tree, each `--against` revision's tree) is a child process; the ways take turns, one child each a round, so that
all see the same machine load.  Medians over the looks; per part, ms a look.  Then the last look's picture against the
exact look at its hour (`preview_psnr_db`): what the drag's preview gives up.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

#: (the class or module, its function, the part's name, whether the part waits for the GPU): the parts of the frame
#: that draws a look; nested parts count within their parent's time too
PARTS = (
    ("frame.FrameRenderer", "_prepare", "prepare", True),
    ("frame.FrameRenderer", "_make_world", "prepare: the world pass made", True),
    ("shadow_map.CloudShadowMap", "update", "prepare: the clouds' shadow map", True),
    ("frame.FrameRenderer", "_plan", "plan", True),
    ("world.WorldPass", "draw", "world pass", True),
    ("sky_view", "build_sky_view_table", "sky-view tables built (wherever)", False),
    ("light_shafts.LightShaftPass", "march", "world: light shafts (with the terrain's coarse depth)", True),
    ("world.TerrainMesh", "draw", "world: terrain (with its tiles' upload)", True),
    ("world.TerrainMesh", "_upload", "world: terrain upload", False),
    ("world.WorldPass", "_draw_sky", "world: the sky's read", True),
    ("impostor_store.ImpostorStore", "update", "impostor updates", True),
    ("cloud_pass.CloudPass", "draw", "cloud pass", True),
    ("frame.FrameRenderer", "display_texture", "the display texture", True),
)


def measure(looks: int, size: tuple[int, int]) -> dict:
    """This process's tree: `looks` looks of a drag from 9:00 on the default scene."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import dataclasses

    from OpenGL import GL

    from cloudcore.atmosphere import sky_view
    from cloudcore.gl import frame, impostor_store, light_shafts, shadow_map, world
    from cloudcore.gl.draw import cloud_pass
    from cloudcore.light.illumination import IlluminationCache, illuminate_direction
    from cloudcore.light.live_air import LiveAir
    from cloudcore.light.relighting import PREVIEW_METHOD, Look
    from cloudcore.model.settings import RenderSettings
    from cloudcore.resources import DEFAULT_SCENE
    from cloudcore.scenes.files import load_scene

    modules = {
        "frame": frame,
        "shadow_map": shadow_map,
        "world": world,
        "sky_view": sky_view,
        "light_shafts": light_shafts,
        "impostor_store": impostor_store,
        "cloud_pass": cloud_pass,
    }
    spent = {name: 0.0 for _, _, name, _ in PARTS}

    def timed(function, name: str, waits: bool):
        def part(*args, **kwargs):
            if waits:
                GL.glFinish()
            start = time.perf_counter()
            result = function(*args, **kwargs)
            if waits:
                GL.glFinish()
            spent[name] += 1e3 * (time.perf_counter() - start)
            return result

        return part

    for owner_name, attribute, name, waits in PARTS:
        module, _, owner = owner_name.partition(".")
        target = getattr(modules[module], owner) if owner else modules[module]
        setattr(target, attribute, timed(getattr(target, attribute), name, waits))

    from app.editor import EDITOR_FRAME_BUDGET_MS

    settings = RenderSettings(frame_budget_ms=EDITOR_FRAME_BUDGET_MS)
    scene = load_scene(DEFAULT_SCENE)
    cache, air = IlluminationCache(), LiveAir()
    renderer = frame.FrameRenderer(*size, illumination=cache, air=air)
    for _ in range(2):  # the exact look before the drag, its impostors made
        renderer.render(scene, time_of_day=9.0, read_back=False, settings=settings)
    spent.update((name, 0.0) for name in spent)
    light_ms, frame_ms, light_cpu_ms, frame_cpu_ms = [], [], [], []
    for step in range(1, looks + 1):
        hours = 9.0 + 0.12 * step
        look = Look(scene.shading, dataclasses.replace(scene.lighting, time_of_day=hours), PREVIEW_METHOD)
        clouds = renderer.drawn_clouds(scene, 0.0)
        start, start_cpu = time.perf_counter(), time.process_time()
        for direction, stale in cache.missing(clouds, look.shading, look.lights(), PREVIEW_METHOD):
            incident = illuminate_direction(stale, look.shading, direction, PREVIEW_METHOD)
            cache.store(stale, look.shading, PREVIEW_METHOD, direction, incident)
        light_ms.append(1e3 * (time.perf_counter() - start))
        light_cpu_ms.append(1e3 * (time.process_time() - start_cpu))
        GL.glFinish()
        start, start_cpu = time.perf_counter(), time.process_time()
        renderer.render(
            scene, time_of_day=hours, illumination_method=PREVIEW_METHOD, read_back=False, settings=settings
        )
        renderer.display_texture()
        GL.glFinish()
        frame_ms.append(1e3 * (time.perf_counter() - start))
        frame_cpu_ms.append(1e3 * (time.process_time() - start_cpu))
    # taken before the picture's check, whose full-3D renders at the exact light are no part of a look
    parts_ms = {name: round(total / looks, 1) for name, total in spent.items()}
    preview_psnr_db = _preview_error(renderer, scene, hours, settings)
    renderer.close()
    air.close()
    return {
        "worker_light_pass_ms": float(np.median(light_ms)),
        "look_frame_ms": float(np.median(frame_ms)),
        # the processor time, llvmpipe's threads' included: what the look costs the machine's cores, which a loaded
        # machine changes far less than the wall clock
        "worker_light_pass_cpu_ms": float(np.median(light_cpu_ms)),
        "look_frame_cpu_ms": float(np.median(frame_cpu_ms)),
        "parts_ms": parts_ms,
        "preview_psnr_db": preview_psnr_db,
    }


def _preview_error(renderer, scene, hours: float, settings) -> float:
    """The PSNR of the last look's picture against the exact look at its hour, both drawn in full 3D (so that no
    impostor left from another light takes part), the look's preview light held from the drag."""
    import dataclasses

    from cloudcore.light.relighting import EXACT_METHOD, PREVIEW_METHOD
    from cloudcore.measure.imagecompare import compare

    full = dataclasses.replace(settings, mode="full")
    pictures = [
        [renderer.render(scene, time_of_day=hours, illumination_method=method, settings=full)[0] for _ in range(2)][-1]
        for method in (PREVIEW_METHOD, EXACT_METHOD)
    ]
    return compare(*pictures).psnr_db


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--looks", type=int, default=8)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--size", default="879x683", help="the viewport's, the editor's at 1280x800")
    parser.add_argument("--against", action="append", default=[], help="NAME=REV: a revision's looks beside")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    if args.child:
        print(json.dumps(measure(args.looks, size)))
        return
    from cloudcore.measure.benchmark import machine, revision_trees, write_report

    here = Path(__file__).resolve().parents[1]
    revisions = dict(item.split("=", 1) for item in args.against)
    with revision_trees(revisions, here) as trees:
        ways = {"this": here, **trees}
        runs = {name: [] for name in ways}
        for _ in range(args.rounds):
            for name, tree in ways.items():
                load = os.getloadavg()[0]
                child = subprocess.run(
                    [sys.executable, str(Path(__file__).resolve()), "--child", "--looks", str(args.looks)]
                    + ["--size", args.size],
                    env={**os.environ, "PYTHONPATH": str(tree)},
                    capture_output=True,
                    text=True,
                    check=True,
                )
                runs[name].append({**json.loads(child.stdout.strip().splitlines()[-1]), "load_average": load})
    write_report({"machine": machine(), "size": args.size, "looks": args.looks, "runs": runs}, args.json)


if __name__ == "__main__":
    main()
