"""The clouds' shadows' cost: making their map, the light pass's share, and a frame with them against one without.

    python scripts/bench_shadows.py [SCENE] [--sizes 640x480,1280x800] [--repeat 15] [--json out/bench_shadows.json]

The map (`cloudcore.gl.shadow_map`) at several resolutions: its making, the median of --repeat (waited for with
glFinish), and the error of the ground's transmittance under it against a map of 2048 texels (over a 600 x 600 grid
of the scene's terrain), at noon, 15:30 and 18:15: what `MAP_RESOLUTION` was chosen by.  The light pass's part (the
sun through the other clouds, `cloudcore.light.illumination.sun_through_others`).  Then
per size a renderer with the shadows and one without (`RenderSettings.cloud_shadows`), full 3D then auto, taking
turns frame by frame so that both see the same machine load; the medians of --repeat frames after --warm-up frames
of the frame's own timings.  The camera and the sun stay still: the map is made once, in the first frame.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from OpenGL import GL  # noqa: E402  (after the platform above)

from cloudcore.gl.context import HeadlessContext  # noqa: E402
from cloudcore.gl.frame import FrameRenderer  # noqa: E402
from cloudcore.gl.shadow_map import CloudShadowMap  # noqa: E402
from cloudcore.light.cloud_shadows import sample_map  # noqa: E402
from cloudcore.light.illumination import shadowing_sun, sun_through_others  # noqa: E402
from cloudcore.light.lighting import scene_lights  # noqa: E402
from cloudcore.measure.benchmark import machine, setting_in_turns, write_report  # noqa: E402
from cloudcore.particles.buffer import ParticleBuffer  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import FULL_3D, RenderSettings  # noqa: E402
from cloudcore.terrain import heightfield_mesh  # noqa: E402

REPRESENTATIONS = {"full": FULL_3D, "auto": RenderSettings()}
TIMINGS = ("world_ms", "cloud_ms", "impostor_update_ms", "frame_ms")
RESOLUTIONS = (256, 384, 512, 768, 1024)
REFERENCE_RESOLUTION = 2048
HOURS = (12.0, 15.5, 18.25)


def map_costs(scene, repeat: int) -> dict:
    """Per resolution, the map's making (ms) and its ground's transmittance against the reference's, per hour."""
    ground, _ = heightfield_mesh(dataclasses.replace(scene.terrain, resolution=600))
    row = {}
    context = HeadlessContext(64, 64)
    shadow_map = CloudShadowMap()
    try:
        for hours in HOURS:
            lights, ambient = scene_lights(dataclasses.replace(scene.lighting, time_of_day=hours))
            particles = ParticleBuffer(scene.clouds, scene.shading, lights, ambient, "preview")
            sun = shadowing_sun(lights)
            seen = {}
            for resolution in (*RESOLUTIONS, REFERENCE_RESOLUTION):
                timed = hours == HOURS[0] and resolution != REFERENCE_RESOLUTION
                times = []
                for turn in range(repeat if timed else 1):
                    # a sun a hair apart each turn: the map is made every time
                    started = time.perf_counter()
                    shadow_map.update(particles, (sun[0], sun[1], sun[2] + 1e-12 * turn), resolution)
                    GL.glFinish()
                    times.append(1e3 * (time.perf_counter() - started))
                if timed:
                    row[f"map_{resolution}_make_ms"] = float(np.median(times))
                seen[resolution] = np.exp(-sample_map(shadow_map.space, shadow_map.read(), ground))
            reference = seen[REFERENCE_RESOLUTION]
            row[f"ground_shadowed_share_{hours}"] = float(np.mean(reference < 0.99))
            for resolution in RESOLUTIONS:
                error = np.abs(seen[resolution] - reference)
                row[f"map_{resolution}_error_mean_{hours}"] = float(error.mean())
                row[f"map_{resolution}_error_p99_{hours}"] = float(np.percentile(error, 99))
    finally:
        shadow_map.close()
        context.close()
    return row


def light_pass_costs(scene, repeat: int) -> dict:
    """The sun through the other clouds, ms (the best of `repeat`)."""
    lights, _ = scene_lights(scene.lighting)
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        sun_through_others(scene.clouds, scene.shading, shadowing_sun(lights))
        times.append(1e3 * (time.perf_counter() - started))
    return {"between_clouds_ms": float(min(times))}


def frame_costs(scene, width: int, height: int, repeat: int, warm_up: int) -> dict:
    """Per representation, with the shadows ("on") and without ("off"), the median of each of `TIMINGS` over
    `repeat` frames; a renderer each (each keeps its own map)."""
    renderers = {turn: FrameRenderer(width, height) for turn in ("on", "off")}
    try:
        costs = setting_in_turns(renderers, scene, REPRESENTATIONS, "cloud_shadows", TIMINGS, repeat, warm_up)
    finally:
        for renderer in renderers.values():
            renderer.close()
    return {"size": f"{width}x{height}", **costs}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--sizes", default="640x480,1280x800")
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--warm-up", type=int, default=5)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(args.scene)
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    report = {
        "machine": machine(),
        "scene": str(args.scene),
        "map": map_costs(scene, args.repeat),
        "light_pass": light_pass_costs(scene, 3),
        "sizes": [frame_costs(scene, width, height, args.repeat, args.warm_up) for width, height in sizes],
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
