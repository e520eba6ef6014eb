"""The light shafts' error against their cost: the world pass with the shafts marched by each number of steps at each
fraction of the screen's resolution, against a reference marched finely at the screen's own, and its time against
the world pass without them.

    python scripts/bench_light_shafts.py [SCENE] [--sizes 640x480,1280x800] [--qualities 12x8,16x4,...]
                                         [--repeat 12] [--json out/bench_light_shafts.json] [--pictures DIR]

Four views of the scene: its camera at its time of day, and three it was not tuned on (toward the low sun at 17:30
from the valley's sunward side's opposite, from 1.5 km up at 16:00, toward the morning sun at 9:00).  Per size and
view, each quality's world pass (`cloudcore.gl.world.WorldPass`, terrain and sky, the clouds' shadow map made by a
renderer for that view) is drawn in turns with the others and with no shafts, each draw waited for (glFinish), the
median of --repeat after one of warm-up; its picture (8-bit sRGB) against the reference's (`REFERENCE`) in dB, and
the shafts' own size: the picture without them against the reference.  What `SHAFT_STEPS` and `SHAFT_COLUMNS`
were chosen by (docs/atmosphere.md#light-shafts).  --pictures DIR writes each view's frame (full 3D, the default
settings) with and without the shafts, side by side, per size: DIR/VIEW_WIDTHxHEIGHT.png.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import imageio.v3 as imageio
import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from OpenGL import GL  # noqa: E402  (after the platform above)

from cloudcore.gl.frame import FrameRenderer  # noqa: E402
from cloudcore.gl.world import WorldPass  # noqa: E402
from cloudcore.light.lighting import scene_lights  # noqa: E402
from cloudcore.light.sky_background import scene_sky  # noqa: E402
from cloudcore.light.terrain_light import terrain_light  # noqa: E402
from cloudcore.maths.colour import linear_to_srgb8  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.model.scene import Camera  # noqa: E402
from cloudcore.model.settings import FULL_3D  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402
from cloudcore.world.camera import projection_matrix, view_matrix  # noqa: E402
from cloudcore.world.sun import sun_direction  # noqa: E402

#: (steps, screen pixels a shaft pixel spans per axis) of the reference
REFERENCE = (96, 1)


def toward_the_sun(hours: float, back_m: float, height_m: float, pitch: float) -> Camera:
    """An eye `back_m` from the scene's origin away from the sun at `hours`, `height_m` up, looking toward it (its
    azimuth), `pitch` (a slope) up."""
    sun = np.asarray(sun_direction(hours))
    level = np.array([sun[0], 0.0, sun[2]]) / np.hypot(sun[0], sun[2])
    eye = -back_m * level + np.array([0.0, height_m, 0.0])
    return Camera(tuple(eye), tuple(eye + 1000.0 * (level + np.array([0.0, pitch, 0.0]))), 60.0)


def views(scene) -> dict:
    """name -> (time of day, camera)."""
    return {
        "default": (scene.lighting.time_of_day, scene.camera),
        "evening_low_sun": (17.5, toward_the_sun(17.5, 2600.0, 500.0, 0.12)),
        "from_1500m": (16.0, toward_the_sun(16.0, 4000.0, 1500.0, -0.1)),
        "morning": (9.0, toward_the_sun(9.0, 2500.0, 400.0, 0.1)),
    }


def world_picture(context) -> np.ndarray:
    return linear_to_srgb8(context.read_linear_rgb())


def timed_draw(world, shafts: bool, context, camera, view, projection, shadows) -> float:
    """Draw `world` with or without `shafts` into `context`'s target, waited for; ms."""
    context.bind_target()
    GL.glFinish()
    start = time.perf_counter()
    world.draw(context, camera, view, projection, shadows=shadows, light_shafts=shafts)
    GL.glFinish()
    return 1e3 * (time.perf_counter() - start)


def write_pictures(scene, width: int, height: int, folder: Path) -> None:
    """Each view's frame with the shafts and without, side by side, into `folder`."""
    folder.mkdir(parents=True, exist_ok=True)
    with FrameRenderer(width, height) as renderer:
        for name, (hours, camera) in views(scene).items():
            frames = [
                renderer.render(
                    scene, time_of_day=hours, camera=camera, settings=dataclasses.replace(FULL_3D, light_shafts=on)
                )[0]
                for on in (True, False)
            ]
            imageio.imwrite(folder / f"{name}_{width}x{height}.png", np.concatenate(frames, axis=1))


def measure(scene, width: int, height: int, qualities, repeat: int) -> dict:
    row = {"size": f"{width}x{height}"}
    with FrameRenderer(width, height) as renderer:
        context = renderer.context
        for name, (hours, camera) in views(scene).items():
            lighting = dataclasses.replace(scene.lighting, time_of_day=hours)
            renderer.render(scene, time_of_day=hours, camera=camera, settings=FULL_3D, read_back=False)
            shadows = renderer.shadow_map
            light, sky = terrain_light(lighting, *scene_lights(lighting)), scene_sky(lighting)
            ways = {"off": WorldPass(scene.terrain, light, sky)}
            ways |= {
                f"{s}x{r}": WorldPass(scene.terrain, light, sky, shaft_steps=s, shaft_reduction=r) for s, r in qualities
            }
            reference = WorldPass(scene.terrain, light, sky, shaft_steps=REFERENCE[0], shaft_reduction=REFERENCE[1])
            view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, width / height)

            drawing = (context, camera, view, projection, shadows)
            timed_draw(reference, True, *drawing)
            truth = world_picture(context)
            times = {way: [] for way in ways}
            for turn in range(repeat + 1):
                for way, world in ways.items():
                    elapsed = timed_draw(world, way != "off", *drawing)
                    if turn:
                        times[way].append(elapsed)
            off_ms = float(np.median(times["off"]))
            row[f"{name}_off_ms"] = off_ms
            for way, world in ways.items():
                timed_draw(world, way != "off", *drawing)
                row[f"{name}_{way}_psnr_db"] = float(compare(world_picture(context), truth).psnr_db)
                if way != "off":
                    row[f"{name}_{way}_added_ms"] = float(np.median(times[way])) - off_ms
            for world in (*ways.values(), reference):
                world.close()
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--sizes", default="640x480,1280x800")
    parser.add_argument("--qualities", default="8x8,12x8,16x8,12x4,16x4,24x4,12x16")
    parser.add_argument("--repeat", type=int, default=12)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--pictures", type=Path, help="write each view with and without shafts here, and stop")
    args = parser.parse_args()
    scene = load_scene(args.scene)
    qualities = [tuple(int(v) for v in quality.split("x")) for quality in args.qualities.split(",")]
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    if args.pictures is not None:
        for width, height in sizes:
            write_pictures(scene, width, height, args.pictures)
        return
    report = {
        "machine": machine(),
        "scene": str(args.scene),
        "reference": f"{REFERENCE[0]}x{REFERENCE[1]}",
        "rows": [measure(scene, width, height, qualities, args.repeat) for width, height in sizes],
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
