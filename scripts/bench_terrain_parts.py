"""Where the terrain's draw spends its time on this machine, and whether its tiles could be coarser.

    python scripts/bench_terrain_parts.py [--sizes 320x240,880x680,1280x960] [--rounds 10]
        [--json out/bench_terrain_parts.json]
    python scripts/bench_terrain_parts.py --errors 0.001,0.002

One process draws the default view in auto mode (`RenderSettings()`) at each size, the terrain's draw
(`world.TerrainMesh.draw`) timed between two `glFinish`, its ways taking turns, two frames each, round after
round: as drawn (`drawn`: the tiles under the clouds' map alone reading the clouds' shadow, baked on the ground
once the map is held), the tiles under the map reading the map itself per pixel (`map_read`: as 3191b42 drew
them), every tile in view reading the map's bake (`every_tile_reads`), no tile reading it (`no_read`), and its depth
alone (`depth`: the same triangles, no colour, no varyings), and as drawn with no pixel (`vertices`: a one-pixel
scissor, so that what is left is llvmpipe's vertex shading, clipping and triangle setup).  Reports the medians (ms)
of the wall clock and of the process's CPU time (all its threads: llvmpipe's rasterising threads too, and less of
the other sessions' load) and the load average.  A size's pixels scale the pixels' share; the triangles' share does
not move.

With `--errors`, instead, the tiles of the default view: the tiles in view and their triangles as drawn (split
while near and rough), as split while near alone (9652f19's rule), and as a split by screen-space error alone
would draw them (a tile split while its height error, `terrain_tiles.tile_errors_m`, over the eye's distance to it
exceeds each angle given, in radians), so that a terrain's cost and error can be judged before it is drawn
(docs/performance.md, "The terrain's pixels off the clouds' map").
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

#: the ways of `--sizes`, in the order they take turns
WAYS = ("drawn", "map_read", "every_tile_reads", "no_read", "depth", "vertices")
#: frames drawn before timing, and in each turn
WARM_UP, PER_TURN = 3, 2


def time_ways(sizes: list[str], rounds: int) -> list[dict]:
    from OpenGL import GL

    from cloudcore.gl import world
    from cloudcore.gl.frame import FrameRenderer
    from cloudcore.measure.benchmark import still_views
    from cloudcore.model.settings import RenderSettings
    from cloudcore.resources import DEFAULT_SCENE
    from cloudcore.scenes.files import load_scene
    from cloudcore.world.terrain_tiles import TerrainTiles

    scene = load_scene(DEFAULT_SCENE)
    time_s, camera = still_views(scene, 1)[0]
    way = {"now": WAYS[0]}
    spent: list[float] = []
    processor: list[float] = []
    draw, under = world.TerrainMesh.draw, TerrainTiles.under_the_clouds_map

    def under_as_the_way_says(tiles, space):
        drawn = under(tiles, space)
        return {"every_tile_reads": np.ones_like(drawn), "no_read": np.zeros_like(drawn)}.get(way["now"], drawn)

    def timed_draw(mesh, camera, view_projection, *args, **kwargs):
        GL.glFinish()
        start, start_processor = time.perf_counter(), time.process_time()
        if way["now"] == "vertices":
            GL.glEnable(GL.GL_SCISSOR_TEST)
            GL.glScissor(0, 0, 1, 1)
            draw(mesh, camera, view_projection, *args, **kwargs)
            GL.glDisable(GL.GL_SCISSOR_TEST)
        elif way["now"] == "depth":
            mesh.draw_depth_full(camera, view_projection)
        elif way["now"] == "map_read":
            mesh._read_baked = False
            draw(mesh, camera, view_projection, *args, **kwargs)
        else:
            draw(mesh, camera, view_projection, *args, **kwargs)
        GL.glFinish()
        spent.append(1e3 * (time.perf_counter() - start))
        processor.append(1e3 * (time.process_time() - start_processor))

    def draw_depth_full(mesh, camera, view_projection):
        program = mesh._programs.program("terrain_depth", {"THROUGH_AIR": 0, "CLOUD_SHADOW_READ": 0}, vertex="terrain")

        def use(_shadow_read, _far_air):
            GL.glUseProgram(program)
            return program

        mesh._draw_tiles(use, camera, view_projection, None)

    TerrainTiles.under_the_clouds_map = under_as_the_way_says
    world.TerrainMesh.draw = timed_draw
    world.TerrainMesh.draw_depth_full = draw_depth_full
    results = []
    for size in sizes:
        width, height = (int(v) for v in size.split("x"))
        times: dict[str, list[float]] = {name: [] for name in WAYS}
        processor_times: dict[str, list[float]] = {name: [] for name in WAYS}
        with FrameRenderer(width, height) as renderer:

            def frames(count: int) -> None:
                for _ in range(count):
                    renderer.render(scene, camera=camera, time_s=time_s, settings=RenderSettings(), read_back=False)

            for name in WAYS:
                way["now"] = name
                frames(WARM_UP)
            for _ in range(rounds):
                for name in WAYS:
                    way["now"] = name
                    spent.clear()
                    processor.clear()
                    frames(PER_TURN)
                    times[name] += spent
                    processor_times[name] += processor
        results.append(
            {
                "size": size,
                "terrain_ms_medians": {name: float(np.median(t)) for name, t in times.items()},
                "terrain_ms": times,
                "terrain_processor_ms_medians": {name: float(np.median(t)) for name, t in processor_times.items()},
                "terrain_processor_ms": processor_times,
                "load_average": os.getloadavg(),
            }
        )
        print(size, {name: round(float(np.median(t)), 1) for name, t in times.items()}, os.getloadavg(), flush=True)
        print("  CPU", {name: round(float(np.median(t)), 1) for name, t in processor_times.items()}, flush=True)
    return results


def tile_errors(angles: list[float]) -> list[dict]:
    from cloudcore.measure.benchmark import still_views
    from cloudcore.resources import DEFAULT_SCENE
    from cloudcore.scenes.files import load_scene
    from cloudcore.world import terrain_tiles
    from cloudcore.world.camera import frustum_planes, projection_matrix, view_matrix
    from cloudcore.world.terrain_tiles import (
        SKIRT_SIDES,
        TILE_FACES,
        TerrainTiles,
        grid_face_count,
        leaf_tiles,
        skirted_sides,
        tile_meshes,
    )

    scene = load_scene(DEFAULT_SCENE)
    _, camera = still_views(scene, 1)[0]
    planes = frustum_planes(projection_matrix(camera.fov_y_deg, 880 / 680) @ view_matrix(camera))
    tiles = TerrainTiles(scene.terrain)
    tiles.update(camera.position)
    frame = tiles.frame

    def counted(name: str, rows: np.ndarray) -> dict:
        rows = rows[np.lexsort((rows[:, 2], rows[:, 1], rows[:, 0]))]
        positions, _ = tile_meshes(scene.terrain, frame, rows)
        tiles.boxes = np.stack([positions.min(axis=1), positions.max(axis=1)], axis=1)
        in_view = tiles.in_view(planes)
        skirts = int(skirted_sides(rows)[in_view].sum())
        per_side = (len(TILE_FACES) - grid_face_count()) // len(SKIRT_SIDES)
        row = {
            "split": name,
            "tiles": len(rows),
            "in_view": int(in_view.sum()),
            "in_view_by_level": np.bincount(rows[in_view, 0]).tolist(),
            "triangles_in_view": int(in_view.sum()) * grid_face_count() + skirts * per_side,
        }
        print(row, flush=True)
        return row

    errors = tiles._errors_m
    rows = [
        counted("drawn: near and rough (SPLIT_DISTANCE, SPLIT_ERROR_RAD)", tiles.tiles.copy()),
        counted("near alone (SPLIT_DISTANCE: 9652f19)", leaf_tiles(frame, camera.position)),
    ]
    distance, error = terrain_tiles.SPLIT_DISTANCE, terrain_tiles.SPLIT_ERROR_RAD
    try:
        terrain_tiles.SPLIT_DISTANCE = np.inf  # split by the error alone
        for angle in angles:
            terrain_tiles.SPLIT_ERROR_RAD = angle
            rows.append(counted(f"error over distance > {angle} rad", leaf_tiles(frame, camera.position, errors)))
    finally:
        terrain_tiles.SPLIT_DISTANCE, terrain_tiles.SPLIT_ERROR_RAD = distance, error
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="320x240,880x680,1280x960")
    parser.add_argument("--rounds", type=int, default=10)
    parser.add_argument("--errors", help="angles (rad), comma-separated: count the tiles a split by error would draw")
    parser.add_argument("--json", type=Path)
    arguments = parser.parse_args()
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    if arguments.errors:
        report = {"errors": tile_errors([float(v) for v in arguments.errors.split(",")])}
    else:
        report = {"sizes": time_ways(arguments.sizes.split(","), arguments.rounds)}
    if arguments.json:
        arguments.json.parent.mkdir(parents=True, exist_ok=True)
        arguments.json.write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
