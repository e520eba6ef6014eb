"""`cloudview truth SCENE --out T.png`: the path-traced reference (Mitsuba 3); with --json, the models against it.

The models are Harris's with each of his illumination methods of `cloudcore.light.shading` and the saturated
eye pass with the exact one, or those --models names (any eye pass with any illumination method).  The
truth and the models both show the clouds over the sky, the terrain and objects left out
(`cloudcore.measure.truth` says what the medium and the lights are); --terrain path traces the terrain too, the
clouds' shadows on it, for a picture alone.  The report renders the truth again
with the next seed, for its own noise, and each model through the GL renderer in full 3D.  --workers N (or
--cluster) path traces the passes of 16 samples on N processes (`cloudcore.cli.workers`): the same picture.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from cloudcore.cli.render import (
    add_scene_argument,
    camera_argument,
    check_outputs,
    check_time_argument,
    image_path,
    pixel_count,
    write_output,
)
from cloudcore.cli.settings_args import add_settings_arguments
from cloudcore.cli.workers import Job, add_workers_arguments, run_job, spread
from cloudcore.light.shading import EYE_PASSES, METHODS
from cloudcore.light.splat_look import LOOK_SETTINGS
from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.measure.benchmark import PSNR_CAP_DB
from cloudcore.measure.imagecompare import compare, diff_image
from cloudcore.measure.truth import (
    DEFAULT_VOXELS_PER_RADIUS,
    SAMPLES_PER_PASS,
    VARIANTS,
    PathTracer,
    mitsuba_variant,
    render_truth,
)
from cloudcore.measure.truth_comparison import BODY_ALPHA, CLOUD_ALPHA, region_errors, truth_regions
from cloudcore.model.errors import SceneError
from cloudcore.model.settings import RenderSettings
from cloudcore.scenes.files import load_scene
from cloudcore.world.sun import scene_hour

REGION_DEFINITION = (
    f"from the truth: sky where its alpha (1 - transmittance along the pixel's central ray) < {CLOUD_ALPHA}, "
    f"silhouette where {CLOUD_ALPHA} <= alpha < {BODY_ALPHA}; the body (alpha >= {BODY_ALPHA}) is lit where the "
    "optical depth toward the sun from the point where the view ray's optical depth reaches 1 is below 1, "
    "shadowed elsewhere"
)


def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise ValueError(text)
    return value


def add_parser(commands) -> None:
    parser = commands.add_parser(
        "truth", help="path trace a reference picture (Mitsuba 3) and compare the shading models with it"
    )
    add_scene_argument(parser)
    parser.add_argument("--out", required=True, type=image_path, help="PNG to write (sRGB, as cloudview render)")
    # path tracing thick clouds is slow on a CPU: smaller than cloudview render's default frame
    parser.add_argument("--width", type=pixel_count, default=160)
    parser.add_argument("--height", type=pixel_count, default=120)
    parser.add_argument("--spp", type=positive_int, default=64, help="samples per pixel (default 64)")
    parser.add_argument("--time-of-day", type=float, help="time of day in hours, overriding the scene's")
    parser.add_argument("--camera-path", help="take the camera from this path of the scene")
    parser.add_argument("--path-time", type=float, default=0.0, help="seconds along --camera-path")
    parser.add_argument("--seed", type=int, default=0, help="the same seed gives the same picture (default 0)")
    parser.add_argument(
        "--voxels-per-radius",
        type=float,
        default=DEFAULT_VOXELS_PER_RADIUS,
        help=f"voxels across the median particle radius (default {DEFAULT_VOXELS_PER_RADIUS:g})",
    )
    parser.add_argument("--variant", choices=VARIANTS, help="Mitsuba variant (default: the first that loads)")
    parser.add_argument(
        "--terrain",
        action="store_true",
        help="path trace the scene's terrain too, the clouds' shadows on it (a picture: not with --json, whose "
        "models are the clouds over the sky)",
    )
    parser.add_argument("--json", type=Path, help="compare the shading models with the truth; write the report here")
    parser.add_argument("--model-images", type=Path, help="with --json: write each model's picture and diff here")
    parser.add_argument(
        "--models",
        type=model_names,
        default=DEFAULT_MODELS,
        help=f"with --json: the models compared, comma-separated (default {','.join(DEFAULT_MODELS)}; "
        "any eye pass-illumination method: yusov-occlusion is Yusov's whole model)",
    )
    # the models' splats per particle or per pixel, with detail noise or not (docs/shading.md, "Per-pixel shading
    # and detail noise")
    add_settings_arguments(parser, only=LOOK_SETTINGS)
    add_workers_arguments(parser, f"passes of {SAMPLES_PER_PASS} samples")
    parser.set_defaults(run=run)


def run(args) -> int:
    try:
        mitsuba_variant(args.variant)
    except ImportError:
        raise SceneError("cloudview truth", "mitsuba", "not installed (pip install 'cloudview[truth]')") from None
    except RuntimeError as error:
        raise SceneError("cloudview truth", "--variant", str(error)) from None
    import imageio.v3 as iio

    check_outputs(args.out, args.json)
    try:  # the models' look, refused before any path is traced
        RenderSettings(**{name: getattr(args, name) for name in LOOK_SETTINGS})
    except ValueError as error:
        raise SceneError("cloudview truth", "settings", str(error)) from None
    if args.terrain and args.json is not None:
        raise SceneError("cloudview truth", "--terrain", "compares no models: the models draw no terrain (drop --json)")
    scene = load_scene(args.scene)
    check_time_argument(args.time_of_day)
    camera = camera_argument(args, scene)
    truth = _render(scene, camera, args, args.seed)
    image = linear_to_srgb8(truth.linear)
    write_output(args.out, lambda path: iio.imwrite(path, image))
    print(
        f"wrote {args.out} ({args.width}x{args.height}, {args.spp} spp, seed {args.seed}, {truth.variant}): "
        f"{truth.seconds:.1f} s, {truth.voxels:,} voxels"
    )
    if args.json is None:
        return 0

    second = _render(scene, camera, args, args.seed + 1)
    noise = compare(image, linear_to_srgb8(second.linear)).psnr_db
    regions = truth_regions(truth.alpha, truth.sun_depth)
    hour = scene_hour(
        scene.lighting
        if args.time_of_day is None
        else dataclasses.replace(scene.lighting, time_of_day=args.time_of_day)
    )
    report = {
        "scene": str(args.scene),
        "width": args.width,
        "height": args.height,
        "camera": dataclasses.asdict(camera),
        "time_of_day": hour,
        "truth": {
            "spp": args.spp,
            "seed": args.seed,
            "seconds": truth.seconds,
            "variant": truth.variant,
            "voxels": truth.voxels,
            "voxels_per_radius": args.voxels_per_radius,
            # the PSNR of one picture against the converged one is about 3 dB above this
            "noise_psnr_db": min(noise, PSNR_CAP_DB),
            "second_seed_seconds": second.seconds,
        },
        "region_definition": REGION_DEFINITION,
        "regions": {name: int(mask.sum()) for name, mask in regions.items()},
        "models": {},
    }
    for name, (model, stats, seconds) in model_renders(scene, camera, args).items():
        report["models"][name] = {
            "seconds": seconds,
            "illumination_ms": stats.illumination_ms,
            "frame_ms": stats.frame_ms,
            "errors": region_errors(image, model, regions),
        }
        if args.model_images is not None:
            write_output(args.model_images / f"{name}.png", lambda path, picture=model: iio.imwrite(path, picture))
            write_output(
                args.model_images / f"{name}_diff.png",
                lambda path, picture=model: iio.imwrite(path, diff_image(image, picture)),
            )
    write_output(args.json, lambda path: path.write_text(json.dumps(report, indent=2) + "\n"))
    print(f"truth noise (seeds {args.seed} and {args.seed + 1}): {noise:.2f} dB")
    for name, model in report["models"].items():
        whole = model["errors"]["image"]
        print(
            f"{name:<16} PSNR {whole['psnr_db']:6.2f} dB, mean luminance error {whole['mean_luminance_error']:+.4f} "
            f"({model['seconds']:.2f} s)"
        )
    print(f"wrote {args.json}")
    return 0


def _render(scene, camera, args, seed: int):
    with tqdm(total=args.spp, desc=f"path tracing (seed {seed})", unit="spp", disable=None, leave=False) as bar:
        try:
            return render_truth(
                scene,
                args.width,
                args.height,
                camera=camera,
                time_of_day=args.time_of_day,
                spp=args.spp,
                seed=seed,
                voxels_per_radius=args.voxels_per_radius,
                variant=args.variant,
                progress=lambda done, total: bar.update(done - bar.n),
                terrain=args.terrain,
                run_passes=(lambda samples, grids: _passes_on_workers(args, camera, seed, samples, grids))
                if spread(args)
                else None,
            )
        except SceneError:  # already says where (a piece that failed on the workers)
            raise
        except ValueError as error:
            raise SceneError(args.scene, "truth", str(error)) from None


def _passes_on_workers(args, camera, seed: int, samples: list[int], grids):
    """The truth's passes on workers (`render_truth`'s run_passes), the medium sent to each rather than built
    again there; its bar is the spp one."""
    job = Job(
        "truth",
        TruthPasses,
        (args.scene, grids, args.width, args.height, camera, args.time_of_day, args.variant, args.terrain, seed),
        pieces=list(enumerate(samples)),
        unit="pass",
        label=lambda index: f"pass {index} (seed {seed})",
        bar={"disable": True},
    )
    return run_job(job, args.workers, args.cluster, args.gpus_per_task)


class TruthPasses:
    """One Mitsuba scene of a truth render: a worker of `cloudcore.cli.workers`, called with (pass number,
    samples), giving `PathTracer.pass_radiance`."""

    def __init__(self, scene_file, grids, width, height, camera, time_of_day, variant, terrain, seed):
        self.tracer = PathTracer(
            load_scene(scene_file),
            width,
            height,
            camera=camera,
            time_of_day=time_of_day,
            variant=variant,
            terrain=terrain,
            grids=grids,
        )
        self.seed = seed

    def __call__(self, piece: tuple[int, int]) -> np.ndarray:
        number, samples = piece
        return self.tracer.pass_radiance(number, samples, self.seed)


#: the models that can be compared with the truth: name -> (eye pass, illumination method)
MODELS = {f"{eye_pass}-{method}": (eye_pass, method) for eye_pass in EYE_PASSES for method in METHODS}
#: those compared unless --models names others: Harris's light pass methods, the saturated eye pass, and it over
#: the multiple-scattering octaves (docs/shading.md, "Octaves")
DEFAULT_MODELS = ("harris-exact", "harris-raster", "harris-preview", "saturated-exact", "saturated-octaves")


def model_names(text: str) -> tuple[str, ...]:
    """--models: names of `MODELS`, comma-separated."""
    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in MODELS]
    if unknown or not names:
        raise ValueError(f"unknown model {', '.join(unknown)}; valid: {', '.join(MODELS)}")
    return names


def model_renders(scene, camera, args) -> dict[str, tuple[np.ndarray, dict, float]]:
    """Each model's full-3D picture of the truth's world (the sky; no terrain, no objects, no air)."""
    # headless: EGL must be chosen before OpenGL is first imported
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from cloudcore.gl import FrameRenderer
    from cloudcore.model.settings import FULL_3D

    world = dataclasses.replace(scene, terrain=None, objects=())
    # the truth's clouds hang in empty space before the sky: the models are drawn without the air too (its shafts
    # and aerial perspective took about 1 dB of every model's PSNR; docs/shading.md, "Five views with the lit face
    # in the eye pass")
    looks = {name: getattr(args, name) for name in LOOK_SETTINGS}
    settings = dataclasses.replace(FULL_3D, light_shafts=False, aerial_perspective=False, **looks)
    renders = {}
    with FrameRenderer(args.width, args.height) as renderer:
        for name in args.models:
            eye_pass, method = MODELS[name]
            model_world = dataclasses.replace(world, shading=dataclasses.replace(world.shading, eye_pass=eye_pass))
            start = time.perf_counter()
            image, stats = renderer.render(
                model_world, camera=camera, time_of_day=args.time_of_day, illumination_method=method, settings=settings
            )
            renders[name] = (image, stats, time.perf_counter() - start)
    return renders
