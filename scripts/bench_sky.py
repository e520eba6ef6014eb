"""The atmosphere's costs: its tables' build times, and the world pass under the physical sky against the gradient.

    python scripts/bench_sky.py [SCENE] [--sizes 640x480,1280x800] [--repeat 15] [--json out/bench_sky.json]

The tables: the transmittance and multiple-scattering tables (built once per air, shipped for the default
one), the sky-view table (built when the sun or the air changes: each new time of day), a new sky's
upward irradiance, and the aerial-perspective volume for the view's eye (each new sun, air or eye altitude) and
its preview, each the best of three builds.  The world pass of the scene's view at each size, under the
two skies in turns (so both see the same machine load), the median of 2 * --repeat draws each: with the
scene's terrain (the sky is skipped where the terrain covers the pixel) and without (the sky on every
pixel); the physical sky's cost is the difference.
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

from cloudcore.atmosphere import aerial_perspective, multiple_scattering, sky_view, transmittance  # noqa: E402
from cloudcore.atmosphere.sky import atmosphere_tables  # noqa: E402
from cloudcore.gl.frame import FrameRenderer  # noqa: E402
from cloudcore.gl.world import WorldPass  # noqa: E402
from cloudcore.light.lighting import atmosphere_parameters, scene_lights  # noqa: E402
from cloudcore.light.sky_background import scene_sky  # noqa: E402
from cloudcore.light.terrain_light import terrain_light  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.model.scene import Air  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402
from cloudcore.world.camera import projection_matrix, view_matrix  # noqa: E402
from cloudcore.world.sun import scene_hour, sun_direction  # noqa: E402


def best_of(build, times: int = 3) -> tuple[float, object]:
    best, result = np.inf, None
    for _ in range(times):
        start = time.perf_counter()
        result = build()
        best = min(best, time.perf_counter() - start)
    return best * 1e3, result


def table_costs(scene) -> dict:
    """The best of three builds of each table, ms."""
    params = atmosphere_parameters(scene.lighting.air)
    sun = sun_direction(scene_hour(scene.lighting))
    transmittance_ms, transmittance_table = best_of(lambda: transmittance.build_transmittance_table(params))
    multiple_ms, multiple_table = best_of(
        lambda: multiple_scattering.build_multiple_scattering_table(params, transmittance_table)
    )
    altitude = scene.lighting.air.origin_altitude_m
    sky_view_ms, _ = best_of(
        lambda: sky_view.build_sky_view_table(params, transmittance_table, multiple_table, altitude, sun[1])
    )
    tables = atmosphere_tables(params)
    eye_altitude = altitude + scene.camera.position[1]
    aerial_ms, _ = best_of(lambda: aerial_perspective.build_aerial_perspective(tables, eye_altitude, sun))
    preview_ms, _ = best_of(lambda: aerial_perspective.build_aerial_perspective(tables, eye_altitude, sun, True))
    return {
        "transmittance_table_ms": transmittance_ms,
        "multiple_scattering_table_ms": multiple_ms,
        "sky_view_table_ms": sky_view_ms,
        "aerial_perspective_volume_ms": aerial_ms,
        "aerial_perspective_preview_volume_ms": preview_ms,
    }


def world_pass_ms(context, world, camera, repeat: int) -> list[float]:
    """Each of `repeat` draws of `world` (terrain and sky, or sky alone), ended by a glFinish, in ms."""
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, context.width / context.height)
    times = []
    for _ in range(repeat):
        context.bind_target()
        start = time.perf_counter()
        world.draw(context, camera, view, projection)
        GL.glFinish()
        times.append((time.perf_counter() - start) * 1e3)
    return times


def world_costs(scene, width: int, height: int, repeat: int) -> dict:
    """The world pass's median time under each sky, drawn in turns in one context: with the scene's terrain, and
    without (the sky on every pixel: its whole cost)."""
    lightings = {sky: dataclasses.replace(scene.lighting, air=Air(sky=sky)) for sky in ("gradient", "physical")}
    skies = {sky: (lighting, scene_sky(lighting)) for sky, lighting in lightings.items()}
    row = {"size": f"{width}x{height}"}
    with FrameRenderer(width, height) as renderer:
        context = renderer.context
        for terrain, label in ((scene.terrain, "terrain_and_sky"), (None, "sky_alone")):
            passes = {
                sky: WorldPass(terrain, terrain_light(lighting, *scene_lights(lighting)), background)
                for sky, (lighting, background) in skies.items()
            }
            times = {sky: [] for sky in passes}
            for _ in range(repeat):
                for sky, world in passes.items():
                    times[sky] += world_pass_ms(context, world, scene.camera, 3)[1:]  # the first after a switch warms
            for sky, world in passes.items():
                row[f"{label}_ms_{sky}"] = float(np.median(times[sky]))
                world.close()
            row[f"{label}_physical_costs_ms"] = row[f"{label}_ms_physical"] - row[f"{label}_ms_gradient"]
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--sizes", default="640x480,1280x800")
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(args.scene)
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    report = {
        "machine": machine(),
        "scene": str(args.scene),
        "tables": table_costs(scene),
        "sizes": [world_costs(scene, width, height, args.repeat) for width, height in sizes],
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
