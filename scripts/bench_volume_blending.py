"""Volume-aware blending against plain blending: picture error against the ray-marched reference and
cost of the cloud pass, side by side in one run. JSON out.

    python scripts/bench_volume_blending.py [--width 320 --height 240] [--repeat 5]
                                            [--json out/bench_volume_blending.json] [--images out/volume_blending]
                                            [--cases two_particles,two_clouds,ground_fog,default_view]

Four cases, each rendered in full 3D with blending "plain" and "volume" interleaved (--repeat times,
the median cloud pass kept): two interpenetrating particles, two interpenetrating clouds (120 particles
of two colours and densities), a cloud lying on the terrain (the world's depth cuts it), and the
default view of the default scene.  For the first three the
reference is `cloudcore.light.volume_blending.ray_marched` of the same particles over the frame's own
world (its colour and depth, rendered without the clouds); the default view's 75,000 particles are too
many for it in numpy, so there the volume picture is compared with the plain one only.  Errors are on
the 8-bit sRGB frames (`cloudcore.measure.imagecompare`).  With --images, each case's plain, volume,
reference and |plain - reference|, |volume - reference| x8 side by side.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.artist.particle_styles import particle_styles  # noqa: E402  (the GL imports need the platform)
from cloudcore.gl.frame import FrameRenderer  # noqa: E402
from cloudcore.gl.volume_blending import batch_splats  # noqa: E402
from cloudcore.light.lighting import scene_lights  # noqa: E402
from cloudcore.light.volume_blending import (  # noqa: E402
    plain_blend,
    ray_distances,
    ray_marched,
    ray_marched_in_tiles,
    screen_tiles,
    tile_pixels,
    volume_blend,
)
from cloudcore.maths.colour import linear_to_srgb8  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare, diff_image  # noqa: E402
from cloudcore.model.scene import Camera, Cloud, Scene, Terrain  # noqa: E402
from cloudcore.model.settings import FULL_3D  # noqa: E402
from cloudcore.particles.batch import splat_batch  # noqa: E402
from cloudcore.particles.buffer import ParticleBuffer  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402
from cloudcore.world.camera import NEAR_PLANE_M, frustum_planes, pixel_rays, projection_matrix, view_matrix  # noqa: E402
from cloudcore.world.terrain import height_at  # noqa: E402

BLENDINGS = ("plain", "volume")


def two_particles() -> Scene:
    """A dense warm particle and a thinner cool one, half inside each other."""
    clouds = (
        Cloud("warm", [[-6.0, 700.0, -300.0, 20.0]], optical_depth=4.0, color=(1.0, 0.55, 0.3)),
        Cloud("cool", [[6.0, 703.0, -308.0, 17.0]], optical_depth=2.0, color=(0.3, 0.55, 1.0)),
    )
    return Scene(clouds=clouds, camera=Camera((0.0, 700.0, -220.0), (0.0, 700.0, -300.0), 40.0), terrain=None)


def two_clouds(seed: int = 5) -> Scene:
    """Two clouds of different colours and densities sharing one region of space."""
    generator = np.random.default_rng(seed)
    clouds = []
    for name, offset, colour, depth in (
        ("warm", [-12.0, 0.0, 0.0], (1.0, 0.55, 0.35), 6.0),
        ("cool", [12.0, 4.0, 6.0], (0.35, 0.55, 1.0), 3.0),
    ):
        centres = generator.normal(0.0, 14.0, (60, 3)) + offset + [0.0, 700.0, -300.0]
        clouds.append(
            Cloud(name, np.column_stack([centres, generator.uniform(8.0, 14.0, 60)]), optical_depth=depth, color=colour)
        )
    return Scene(clouds=tuple(clouds), camera=Camera((0.0, 700.0, -150.0), (0.0, 700.0, -300.0), 40.0), terrain=None)


def ground_fog(seed: int = 2) -> Scene:
    """A flat cloud of 80 particles lying on the default terrain, seen from just above it: the world's
    depth cuts the particles where they meet the ground."""
    terrain = Terrain()
    x, z = 0.0, -300.0
    ground = float(height_at(terrain, np.array([x]), np.array([z]))[0])
    generator = np.random.default_rng(seed)
    centres = generator.normal(0.0, 12.0, (80, 3)) * [2.0, 0.6, 1.0] + [x, ground + 2.0, z]
    fog = Cloud("fog", np.column_stack([centres, generator.uniform(10.0, 16.0, 80)]), optical_depth=2.0)
    camera = Camera((x, ground + 25.0, z + 120.0), (x, ground, z), 40.0)
    return Scene(clouds=(fog,), camera=camera, terrain=terrain)


def scene_batch(scene: Scene, size):
    """(every particle of the scene in one far-to-near batch seen from its camera, view, projection)."""
    camera = scene.camera
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, size[0] / size[1])
    lights, ambient = scene_lights(scene.lighting)
    styles = particle_styles(scene.clouds, scene.lighting)
    particles = ParticleBuffer(scene.clouds, scene.shading, lights, ambient, styles=styles)
    frustum = frustum_planes(projection @ view)
    batch = splat_batch(particles, range(len(scene.clouds)), camera.position, time_s=0.0, frustum=frustum)
    return batch, view, projection


def reference(renderer: FrameRenderer, scene: Scene, steps: int) -> np.ndarray:
    """The ray-marched frame, linear (height, width, 3): the particles over the world the renderer draws."""
    width, height = renderer.size
    renderer.render(dataclasses.replace(scene, clouds=()), settings=FULL_3D)
    world = renderer.context.read_linear_rgb().reshape(-1, 3)
    batch, view, projection = scene_batch(scene, renderer.size)
    rays = pixel_rays(scene.camera, width, height).reshape(-1, 3)
    opaque = ray_distances(renderer.context.read_depth(), rays, view, projection)
    background = np.column_stack([world, np.zeros(len(world))])
    tiles = screen_tiles(batch.centres - batch.eye, batch.radii, view, projection, renderer.size, NEAR_PLANE_M)
    marched = ray_marched_in_tiles(batch_splats(batch, view), rays, background, opaque, tiles, steps)
    return marched[:, :3].reshape(height, width, 3).astype(np.float32)


def densest_tiles(renderer: FrameRenderer, scene: Scene, count: int, steps: int) -> list[dict]:
    """RMS error (linear RGB) against the ray march on the `count` tiles listing the most splats, of
    plain blending, the volume pass as built (holding the front part) and Yusov's merged volume."""
    width, height = renderer.size
    renderer.render(dataclasses.replace(scene, clouds=()), settings=FULL_3D)
    world = np.column_stack([renderer.context.read_linear_rgb().reshape(-1, 3), np.zeros(width * height)])
    batch, view, projection = scene_batch(scene, renderer.size)
    rays = pixel_rays(scene.camera, width, height).reshape(-1, 3)
    opaque = ray_distances(renderer.context.read_depth(), rays, view, projection)
    tiles = screen_tiles(batch.centres - batch.eye, batch.radii, view, projection, renderer.size, NEAR_PLANE_M)
    drawn = batch_splats(batch, view)
    rows = []
    for tile in np.argsort(-np.diff(tiles.starts.astype(np.int64)), kind="stable")[:count]:
        listed = tiles.entries[tiles.starts[tile] : tiles.starts[tile + 1]]
        subset, pixels = drawn.taken(listed), tile_pixels(tiles, int(tile))
        truth = ray_marched(subset, rays[pixels], world[pixels], opaque[pixels], steps)[:, :3]
        pictures = {
            "plain": plain_blend(subset, rays[pixels], world[pixels], opaque[pixels]),
            "volume": volume_blend(subset, rays[pixels], world[pixels], opaque[pixels]),
            "yusov_merged": volume_blend(subset, rays[pixels], world[pixels], opaque[pixels], hold="merged"),
        }
        row = {"tile": int(tile), "splats": len(listed)}
        row |= {f"{name}_rms": float(np.sqrt(np.mean((p[:, :3] - truth) ** 2))) for name, p in pictures.items()}
        rows.append(row)
        print(row)
    return rows


def measure(renderer: FrameRenderer, name: str, scene: Scene, repeat: int, steps: int | None, images: Path | None):
    frames, cloud_ms = {}, {blending: [] for blending in BLENDINGS}
    for _ in range(repeat):
        for blending in BLENDINGS:  # interleaved, so both see the same machine
            settings = dataclasses.replace(FULL_3D, blending=blending)
            frames[blending], stats = renderer.render(scene, settings=settings)
            cloud_ms[blending].append(stats.cloud_ms)
    row = {"case": name, "particles": int(sum(len(c.particles) for c in scene.clouds))}
    for blending in BLENDINGS:
        row[f"{blending}_cloud_ms"] = float(np.median(cloud_ms[blending]))
    row["volume_over_plain_cost"] = row["volume_cloud_ms"] / max(row["plain_cloud_ms"], 1e-9)
    volume_vs_plain = compare(frames["volume"], frames["plain"])
    row["volume_vs_plain_psnr_db"], row["volume_vs_plain_max"] = volume_vs_plain.psnr_db, volume_vs_plain.max_abs
    panels = [frames["plain"], frames["volume"]]
    if steps is not None:
        truth = linear_to_srgb8(reference(renderer, scene, steps))
        for blending in BLENDINGS:
            difference = compare(frames[blending], truth)
            row[f"{blending}_psnr_db"], row[f"{blending}_max"] = difference.psnr_db, difference.max_abs
        panels += [truth, diff_image(frames["plain"], truth), diff_image(frames["volume"], truth)]
    else:
        panels.append(diff_image(frames["plain"], frames["volume"]))
    if images is not None:
        import imageio.v3 as iio

        images.mkdir(parents=True, exist_ok=True)
        iio.imwrite(images / f"{name}.png", np.concatenate(panels, axis=1))
    print(row)
    return row


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1024, help="ray-march intervals per pixel")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--images", type=Path)
    parser.add_argument("--cases", help="comma-separated names of the cases to run (default: all)")
    parser.add_argument(
        "--densest-tiles",
        type=int,
        default=3,
        help="on the default view, this many of the tiles listing the most splats: plain, volume and Yusov's "
        "merged volume against the ray march (numpy, linear RGB)",
    )
    args = parser.parse_args(argv)
    cases = [
        ("two_particles", two_particles(), args.steps),
        ("two_clouds", two_clouds(), args.steps),
        ("ground_fog", ground_fog(), args.steps),
        ("default_view", load_scene(args.scene), args.steps),
    ]
    if args.cases:
        cases = [case for case in cases if case[0] in args.cases.split(",")]
    with FrameRenderer(args.width, args.height) as renderer:
        features = renderer.volume_features
        rows = [measure(renderer, name, scene, args.repeat, steps, args.images) for name, scene, steps in cases]
        dense = densest_tiles(renderer, load_scene(args.scene), args.densest_tiles, args.steps)
    report = {
        "machine": machine(),
        "size": [args.width, args.height],
        "gpu_features": dataclasses.asdict(features),
        "cases": rows,
        "densest_tiles": dense,
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
