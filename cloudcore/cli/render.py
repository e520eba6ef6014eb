"""`cloudview render SCENE --out FILE.png`: one frame, headless (EGL), with optional stats."""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
from pathlib import Path

from cloudcore.cli.settings_args import add_settings_arguments, settings_from
from cloudcore.maths.paths import camera_on_path
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Camera
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene
from cloudcore.scenes.limits import MAX_FRAME_SIDE
from cloudcore.stats.heatmap import heat_image
from cloudcore.stats.overdraw import scene_block_overdraw_statistics


def add_parser(commands) -> None:
    parser = commands.add_parser("render", help="render one frame to a PNG, headless")
    add_scene_argument(parser)
    parser.add_argument(
        "--out", required=True, type=image_path, help="image to write (PNG; its suffix picks the format)"
    )
    parser.add_argument("--width", type=pixel_count, default=640)
    parser.add_argument("--height", type=pixel_count, default=480)
    parser.add_argument("--time-of-day", type=float, help="time of day in hours, overriding the scene's")
    parser.add_argument("--camera-path", help="take the camera from this path of the scene")
    parser.add_argument("--path-time", type=float, default=0.0, help="seconds along --camera-path (default 0)")
    parser.add_argument("--overdraw", type=image_path, help="write the overdraw heat map here (PNG)")
    parser.add_argument("--stats", type=Path, help="write frame statistics, overdraw included, here (JSON)")
    # one frame: the reference picture unless asked otherwise (impostors pay off over many frames)
    add_settings_arguments(parser, default_mode="full")
    parser.set_defaults(run=run)


def add_scene_argument(parser) -> None:
    """The optional SCENE argument: without it, the built-in default scene (shipped in the package)."""
    parser.add_argument(
        "scene", nargs="?", default=str(DEFAULT_SCENE), help="scene file (.toml); default: the built-in valley scene"
    )


def pixel_count(text: str) -> int:
    """An image side in pixels; argparse names this function in its refusal."""
    value = int(text)
    if not 1 <= value <= MAX_FRAME_SIDE:
        raise ValueError(text)
    return value


def image_path(text: str) -> Path:
    """An image to write, its suffix one of a format Pillow writes: refused with the arguments, before any work
    (without one the picture was rendered and then lost, in a traceback)."""
    path = Path(text)
    if path.suffix.lower() not in _image_suffixes():
        raise argparse.ArgumentTypeError(f"{text!r} is not an image file name: end it in .png (or .jpg, .tif, ...)")
    return path


@functools.cache
def _image_suffixes() -> frozenset[str]:
    from PIL import Image

    Image.init()
    return frozenset(suffix for suffix, format_ in Image.registered_extensions().items() if format_ in Image.SAVE)


def check_outputs(*paths: Path | None) -> None:
    """Before the work: every output given can be written, its folder made, and is not a folder itself (a
    benchmark wrote its report to a folder after minutes of frames, and lost them in a traceback)."""
    for path in paths:
        if path is None:
            continue
        if path.is_dir():
            raise SceneError(str(path), "output", "is a folder; name a file in it")
        write_output(path, lambda _: None)  # makes its folder
        if not os.access(path.parent, os.W_OK):
            raise SceneError(str(path), "output", "its folder is not writable")


def check_time_argument(hours: float | None) -> None:
    """--time-of-day, when given, is an hour of the day."""
    if hours is not None and not 0.0 <= hours <= 24.0:
        raise SceneError("--time-of-day", "time_of_day", f"must be within [0, 24] hours, got {hours}")


def camera_argument(args, scene) -> Camera:
    """The scene's camera, or the one `--path-time` seconds along `--camera-path`."""
    if args.camera_path is None:
        return scene.camera
    try:
        path = scene.camera_path(args.camera_path)
    except KeyError as error:
        raise SceneError(args.scene, "camera_paths", error.args[0]) from None
    if not math.isfinite(args.path_time):
        raise SceneError("--path-time", "path_time", f"must be finite seconds, got {args.path_time}")
    return camera_on_path(path, args.path_time, scene.camera.fov_y_deg)


def run(args) -> int:
    check_outputs(args.out, args.overdraw, args.stats)
    scene = load_scene(args.scene)
    check_time_argument(args.time_of_day)
    settings = settings_from(args)
    camera = camera_argument(args, scene)
    # headless: EGL must be chosen before OpenGL is first imported
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    import imageio.v3 as iio

    from cloudcore.gl import FrameRenderer

    with FrameRenderer(args.width, args.height, remember_costs=True) as renderer:
        image, stats = renderer.render(scene, time_of_day=args.time_of_day, camera=camera, settings=settings)
        if args.overdraw or args.stats:
            counts, overdraw = renderer.measure_overdraw()
            stats = stats.with_overdraw(overdraw)
    report = stats.as_dict()
    if stats.overdraw is not None:
        report |= scene_block_overdraw_statistics(scene.clouds)  # Wang's view-independent counterpart
    write_output(args.out, lambda path: iio.imwrite(path, image))
    if args.overdraw:
        write_output(args.overdraw, lambda path: iio.imwrite(path, heat_image(counts)[0][..., :3]))
    if args.stats:
        write_output(args.stats, lambda path: path.write_text(json.dumps(report, indent=2) + "\n"))
    print(
        f"wrote {args.out} ({args.width}x{args.height}): frame {stats.frame_ms:.1f} ms "
        f"(plan {stats.plan_ms:.1f}, world {stats.world_ms:.1f}, clouds {stats.cloud_ms:.1f}; CPU {stats.cpu_ms:.1f}, "
        f"GPU {stats.world_gpu_ms + stats.impostor_update_gpu_ms + stats.cloud_gpu_ms:.1f}), "
        f"{stats.particles_drawn} particles, {stats.clouds_drawn} clouds drawn, "
        f"{stats.clouds_culled} culled"
    )
    if stats.overdraw is not None:
        overdraw = stats.overdraw
        print(
            f"overdraw: mean {overdraw.mean:.2f}, max {overdraw.max:.0f} "
            f"(analytic estimate {overdraw.analytic:.2f}); cloud blocks: mean "
            f"{report['block_overdraw_mean']:.2f}, max {report['block_overdraw_max']:.2f} over {report['blocks']}"
        )
    return 0


def write_output(path: Path, write):
    """Create the parent folder, then `write(path)` and return what it returns; an unwritable path is a one-line
    error."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        return write(path)
    except OSError as error:
        raise SceneError(str(path), "output", error.strerror or str(error)) from None
