"""The shading models against saved path-traced truths, per view and region (docs/shading.md, "Truths at 160x120").

    python scripts/truth_tables.py make default --size 160x120 --spp 32 --seeds 0,1     # path trace, save
    python scripts/truth_tables.py compare default below_terrain --size 160x120 --json out/truth_tables.json

The views are the default scene's particles at albedo 0.99 (`VIEWS`: the scene's camera, into the sun through a
thin cloud, from below a thick one, a field at sunset; `below_terrain` is the view from below with the terrain path
traced too, its ground sending light up into the cloud's base).  `make` renders a view's truth for each seed
(`render_truth`) and saves it as `docs/truths/VIEW_WxH_sSEED.npz` (linear RGB, alpha and depth toward the sun as
float32, and the CPU seconds it took); `compare` draws each model as `cloudview truth` does (full 3D, no air: the
truth has the clouds over the sky) and prints, per view, each model's PSNR and mean luminance error per region
against seed 0 and the image PSNR against the seeds' mean, with the seeds' own agreement.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np

from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.measure.truth import render_truth
from cloudcore.measure.truth_comparison import region_errors, truth_regions
from cloudcore.model.scene import Camera
from cloudcore.scenes.files import load_scene

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "cloudcore" / "resources" / "scenes" / "valley.toml"
TRUTHS = ROOT / "docs" / "truths"
#: view -> (camera (position, look at) or None for the scene's, time of day or None, {cloud: optical depth},
#: whether the terrain is path traced); all at albedo 0.99
VIEWS = {
    "default": (None, None, {}, False),
    "sun": (((2214.0, 625.0, -2231.0), (1516.0, 1136.0, -1984.0)), None, {"cumulus_03": 1.0}, False),
    "below": (((836.0, 380.0, 900.0), (836.0, 1000.0, 700.0)), None, {}, False),
    "below_terrain": (((836.0, 380.0, 900.0), (836.0, 1000.0, 700.0)), None, {}, True),
    "sunset": (None, 18.75, {}, False),
}
ALBEDO = 0.99
MODELS = (
    "harris-exact",
    "saturated-exact",
    "yusov-occlusion",
    "saturated-octaves",
    "saturated-octaves-lit-face",
    "saturated-octaves-lit-face+bounce",
)
REGIONS = ("image", "silhouette", "lit", "shadowed")


def view_scene(name: str):
    """The default scene as view `name` shows it, and whether its truth has the terrain."""
    camera, hour, depths, terrain = VIEWS[name]
    scene = load_scene(SCENE)
    clouds = tuple(
        dataclasses.replace(cloud, optical_depth=depths[cloud.name]) if cloud.name in depths else cloud
        for cloud in scene.clouds
    )
    scene = dataclasses.replace(
        scene, clouds=clouds, shading=dataclasses.replace(scene.shading, albedo=ALBEDO), objects=()
    )
    if camera is not None:
        scene = dataclasses.replace(scene, camera=Camera(camera[0], camera[1], scene.camera.fov_y_deg))
    if hour is not None:
        scene = dataclasses.replace(scene, lighting=dataclasses.replace(scene.lighting, time_of_day=hour))
    return scene, terrain


def truth_path(folder: Path, view: str, width: int, height: int, seed: int) -> Path:
    return folder / f"{view}_{width}x{height}_s{seed}.npz"


def make(args) -> None:
    for view in args.views:
        scene, terrain = view_scene(view)
        for seed in args.seeds:
            start = time.process_time()
            truth = render_truth(scene, args.width, args.height, spp=args.spp, seed=seed, terrain=terrain)
            path = truth_path(args.truths, view, args.width, args.height, seed)
            path.parent.mkdir(parents=True, exist_ok=True)
            np.savez_compressed(
                path,
                linear=truth.linear.astype(np.float32),
                alpha=truth.alpha.astype(np.float32),
                sun_depth=truth.sun_depth.astype(np.float32),
                spp=args.spp,
                cpu_seconds=time.process_time() - start,
            )
            print(f"wrote {path} ({args.spp} spp, {time.process_time() - start:.0f} CPU s)", flush=True)


def compare(args) -> None:
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # before OpenGL is first imported
    from cloudcore.gl import FrameRenderer
    from cloudcore.model.settings import FULL_3D

    settings = dataclasses.replace(FULL_3D, light_shafts=False, aerial_perspective=False)
    report = {}
    with FrameRenderer(args.width, args.height) as renderer:
        for view in args.views:
            seeds = [np.load(truth_path(args.truths, view, args.width, args.height, seed)) for seed in (0, 1)]
            truths = [linear_to_srgb8(seed["linear"].astype(np.float64)) for seed in seeds]
            mean = linear_to_srgb8(0.5 * sum(seed["linear"].astype(np.float64) for seed in seeds))
            regions = truth_regions(seeds[0]["alpha"], seeds[0]["sun_depth"])
            scene, terrain = view_scene(view)
            # the bounce takes the terrain's colour; a view of the terrain in the picture would need it drawn too
            world = scene if terrain else dataclasses.replace(scene, terrain=None)
            rows = {"the truth's noise, seed 1 against seed 0": region_errors(truths[0], truths[1], regions)}
            for name in args.models:
                model, bounce = (name.removesuffix("+bounce"), name.endswith("+bounce"))
                eye_pass, method = model.split("-", 1)
                shading = dataclasses.replace(world.shading, eye_pass=eye_pass, ground_bounce=bounce)
                image, _ = renderer.render(
                    dataclasses.replace(world, shading=shading), illumination_method=method, settings=settings
                )
                rows[name] = region_errors(truths[0], image, regions)
                rows[name]["against the seeds' mean"] = region_errors(mean, image, {"image": regions["image"]})
                if args.images is not None:
                    import imageio.v3 as iio

                    args.images.mkdir(parents=True, exist_ok=True)
                    iio.imwrite(args.images / f"{view}_{name}.png", image)
            report[view] = {"spp": [int(seed["spp"]) for seed in seeds], "rows": rows}
            print(_table(view, rows, truths[0], regions, report[view]["spp"]), flush=True)
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(report, indent=1, default=float) + "\n")


def _table(view: str, rows: dict, truth, regions, spp) -> str:
    lines = [
        f"{view} ({truth.shape[1]}x{truth.shape[0]}, {spp[0]} and {spp[1]} samples a pixel)",
        "",
        "| model | " + " | ".join(REGIONS) + " | image against the seeds' mean |",
        "| --- |" + " --- |" * (len(REGIONS) + 1),
    ]
    for name, errors in rows.items():
        cells = [
            f"{errors[r]['psnr_db']:.1f} dB, {errors[r]['mean_luminance_error']:+.3f}" if errors[r]["pixels"] else "-"
            for r in REGIONS
        ]
        mean = errors.get("against the seeds' mean")
        against_mean = f"{mean['image']['psnr_db']:.1f} dB" if mean else ""
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {against_mean} |")
    first = next(iter(rows.values()))
    lines.append(
        "| the truth's luminance | "
        + " | ".join(f"{first[r]['truth_luminance']:.3f} ({first[r]['pixels']} px)" for r in REGIONS)
        + " | |"
    )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("make", "compare"))
    parser.add_argument("views", nargs="+", choices=tuple(VIEWS))
    parser.add_argument("--truths", type=Path, default=TRUTHS, help=f"the truths' folder (default {TRUTHS})")
    parser.add_argument("--size", default="160x120", help="WIDTHxHEIGHT (default 160x120)")
    parser.add_argument("--spp", type=int, default=32, help="make: samples per pixel (default 32)")
    parser.add_argument("--seeds", default="0,1", help="make: the seeds, comma-separated (default 0,1)")
    parser.add_argument("--models", default=",".join(MODELS), help="compare: the models (EYE-METHOD[+bounce])")
    parser.add_argument("--json", type=Path, help="compare: write the numbers here")
    parser.add_argument("--images", type=Path, help="compare: write each model's picture here")
    args = parser.parse_args()
    args.width, args.height = (int(v) for v in args.size.split("x"))
    args.seeds = [int(s) for s in args.seeds.split(",")]
    args.models = args.models.split(",")
    make(args) if args.action == "make" else compare(args)


if __name__ == "__main__":
    main()
