"""What each part of the world around the clouds costs the default view's auto frame: the shadows, the air, the
physical sky, the valley's mountains and horizon, side by side in one run.

    python scripts/bench_atmosphere_parts.py [--sizes 880x680] [--frames 30] [--warm-up 8]
                                             [--json out/bench_atmosphere_parts.json]

Each way is its own renderer drawing the default view in auto mode (`RenderSettings()` but for what it turns
off); the ways take turns frame by frame, so that all see the same machine load.  From everything to the plain
world of before issue 52, one part off at a time: `all`; `no_shafts` (`light_shafts` off); `no_shadows` (and
`cloud_shadows` off); `no_air` (and
`aerial_perspective` off); `patch` (and the terrain without `relief` and `reach`: the 6 km valley of before);
`gradient` (and the gradient sky: the plain world, drawn by this tree's world pass).  The medians of
`FrameStats.frame_ms`, `world_ms` and `cloud_ms` after the warm-up, ms.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402  (after the platform above)
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

TIMINGS = ("frame_ms", "world_ms", "cloud_ms")


def ways(scene) -> dict:
    """name -> (scene, settings): everything, then one part off after another."""
    settings = RenderSettings()
    no_shafts = dataclasses.replace(settings, light_shafts=False)
    no_shadows = dataclasses.replace(no_shafts, cloud_shadows=False)
    no_air = dataclasses.replace(no_shadows, aerial_perspective=False)
    patch = dataclasses.replace(scene, terrain=dataclasses.replace(scene.terrain, relief=0.0, reach=0.0))
    lighting = patch.lighting
    gradient = dataclasses.replace(
        patch, lighting=dataclasses.replace(lighting, air=dataclasses.replace(lighting.air, sky="gradient"))
    )
    return {
        "all": (scene, settings),
        "no_shafts": (scene, no_shafts),
        "no_shadows": (scene, no_shadows),
        "no_air": (scene, no_air),
        "patch": (patch, no_air),
        "gradient": (gradient, no_air),
    }


def part_costs(scene, width: int, height: int, frames: int, warm_up: int) -> dict:
    drawn = ways(scene)
    renderers = {name: FrameRenderer(width, height) for name in drawn}
    times = {name: [] for name in drawn}
    try:
        for frame in range(warm_up + frames):
            for name, (way_scene, settings) in drawn.items():
                _, stats = renderers[name].render(way_scene, settings=settings, read_back=False)
                if frame >= warm_up:
                    times[name].append([getattr(stats, timing) for timing in TIMINGS])
    finally:
        for renderer in renderers.values():
            renderer.close()
    row = {"size": f"{width}x{height}"}
    for name, values in times.items():
        medians = np.median(np.array(values), axis=0)
        row.update({f"{name}_{timing}": float(m) for timing, m in zip(TIMINGS, medians, strict=True)})
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="880x680")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--warm-up", type=int, default=8)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(DEFAULT_SCENE)
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    report = {
        "machine": machine(),
        "sizes": [part_costs(scene, width, height, args.frames, args.warm_up) for width, height in sizes],
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
