"""Splats as point sprites against quads, and the cost of a draw call: the numbers behind
`cloudcore.particles.point_sprites` (SHORTEST_POINT_RUN). JSON out.

    python scripts/bench_point_sprites.py [cloudcore/resources/scenes/valley.toml] [--repeat 15]
                                          [--json out/bench_point_sprites.json]

Draws the particles of the scene's largest cloud, seen from the scene's eye,
into impostor textures of several sides (through the impostor's own frustum)
and onto a 640x480 screen, as quads and as points, each timed to glFinish
(best of --repeat); and the same batch cut into 1, 256 and 1024 runs of quads,
whose slope is the cost of one more draw.  The images of both ways are
compared (largest difference, 8-bit levels).
"""

from __future__ import annotations

import argparse
import os
import time
from functools import partial
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from OpenGL import GL  # noqa: E402  (the GL imports need the platform above)

import cloudcore.gl.splats as splats_module  # noqa: E402
from cloudcore.gl.context import HeadlessContext  # noqa: E402
from cloudcore.gl.splats import SplatPass  # noqa: E402
from cloudcore.gl.targets import TextureTarget  # noqa: E402
from cloudcore.light.lighting import scene_lights  # noqa: E402
from cloudcore.lod.impostors import impostor_view  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.particles.batch import splat_batch  # noqa: E402
from cloudcore.particles.buffer import ParticleBuffer  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402
from cloudcore.world.camera import projection_matrix, view_matrix  # noqa: E402


def timed_ms(draw, repeat: int) -> float:
    """Best of `repeat` runs of `draw`, to glFinish, in milliseconds."""
    best = np.inf
    for _ in range(repeat):
        GL.glFinish()
        start = time.perf_counter()
        draw()
        GL.glFinish()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best


def draw_into(target, splats, batch, view, projection, point_sprites: bool) -> int:
    """Clear `target` and draw `batch` into it; returns the particles drawn as points."""
    target.bind_cleared()
    return splats.draw(batch, view, projection, depth_test=False, point_sprites=point_sprites)


def given_runs(edges, mask) -> list[tuple[int, int, bool]]:
    """Runs of quads cut at `edges`, whatever the mask: stands in for `draw_runs` to time draw calls."""
    return [(int(a), int(b), False) for a, b in zip(edges[:-1], edges[1:])]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    cloud = max(scene.clouds, key=lambda c: len(c.particles))
    lights, ambient = scene_lights(scene.lighting)
    particles = ParticleBuffer((cloud,), scene.shading, lights, ambient, "raster")
    eye = np.asarray(scene.camera.position, dtype=np.float64)
    centre = cloud.centres.mean(axis=0)
    radius = float(np.max(np.linalg.norm(cloud.centres - centre, axis=1) + cloud.radii))
    impostor = impostor_view(centre, radius, eye)
    screen = (view_matrix(scene.camera), projection_matrix(scene.camera.fov_y_deg, 640 / 480))

    context = HeadlessContext(64, 64)
    context.make_current()
    splats = SplatPass()
    batch = splat_batch(particles, [0], eye)
    rows = []
    for name, (width, height), (view, projection) in [
        *[(f"impostor {side}", (side, side), (impostor.view, impostor.projection)) for side in (32, 64, 128, 256)],
        ("screen 640x480", (640, 480), screen),
    ]:
        target = TextureTarget(width, height)
        row = {"target": name, "particles": len(batch)}
        pictures = {}
        for key, point_sprites in (("quads", False), ("points", True)):
            draw = partial(draw_into, target, splats, batch, view, projection, point_sprites)
            row[f"{key}_ms"] = timed_ms(draw, args.repeat)
            row[f"{key}_us_per_particle"] = 1e3 * row[f"{key}_ms"] / len(batch)
            row[f"{key}_drawn_as_points"] = draw()
            pictures[key] = target.read()
        levels = np.abs(np.clip(pictures["points"], 0, 1) - np.clip(pictures["quads"], 0, 1)) * 255.0
        row["largest_difference_levels"] = float(levels.max())
        target.close()
        rows.append(row)

    # the cost of a draw: the same quads cut into more runs (draw_runs replaced, for this measurement only)
    target = TextureTarget(128, 128)
    run_costs = {}
    for count in (1, 256, 1024):
        edges = np.linspace(0, len(batch), count + 1).astype(int)
        splats_module.draw_runs = partial(given_runs, edges)
        draw = partial(draw_into, target, splats, batch, impostor.view, impostor.projection, False)
        run_costs[count] = timed_ms(draw, args.repeat)
    target.close()
    per_draw_us = 1e3 * (run_costs[1024] - run_costs[1]) / 1023
    saved_us = np.median([row["quads_us_per_particle"] - row["points_us_per_particle"] for row in rows[:4]])
    report = {
        "scene": args.scene,
        "cloud": cloud.name,
        "machine": machine(),
        "renderer": GL.glGetString(GL.GL_RENDERER).decode(),
        "draws": rows,
        "quads_in_runs_ms": run_costs,
        "us_per_extra_draw": per_draw_us,
        "us_saved_per_particle_as_point": float(saved_us),
        # a run of points costs one more draw call on each side: it pays beyond this many particles
        "shortest_point_run_that_pays": float(2.0 * per_draw_us / saved_us) if saved_us > 0 else None,
    }
    splats.close()
    context.close()
    write_report(report, args.json)


if __name__ == "__main__":
    main()
