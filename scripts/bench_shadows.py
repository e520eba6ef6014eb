"""The clouds' shadows' map: its making and its error at each resolution, and the light pass's share.

    python scripts/bench_shadows.py [SCENE] [--repeat 15] [--json out/bench_shadows.json]

The map (`cloudcore.gl.shadow_map`) at several resolutions: its making, the median of --repeat (waited for with
glFinish), and the error of the ground's transmittance under it against a map of 2048 texels (over a 600 x 600 grid
of the scene's terrain), at noon, 15:30 and 18:15: what `MAP_RESOLUTION` was chosen by.  The light pass's part (the
sun through the other clouds, `cloudcore.light.illumination.sun_through_others`).  A frame with the shadows against
one without is the suite `world`'s (`cloudview bench --suite world --cases shadows`).
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
from cloudcore.gl.shadow_map import CloudShadowMap  # noqa: E402
from cloudcore.light.cloud_shadows import sample_map  # noqa: E402
from cloudcore.light.illumination import shadowing_sun, sun_through_others  # noqa: E402
from cloudcore.light.lighting import scene_lights  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.particles.buffer import ParticleBuffer  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402
from cloudcore.world.terrain import heightfield_mesh  # noqa: E402

RESOLUTIONS = (128, 192, 256, 384, 512, 768, 1024)
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(args.scene)
    report = {
        "machine": machine(),
        "scene": str(args.scene),
        "map": map_costs(scene, args.repeat),
        "light_pass": light_pass_costs(scene, 3),
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
