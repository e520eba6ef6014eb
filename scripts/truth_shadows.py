"""The clouds' shadows on the ground against the path-traced truth: where they fall and how deep (issue 52).

    python scripts/truth_shadows.py [SCENE] [--size 160x120] [--spp 32] [--time-of-day 15.5]
                                    [--json out/truth_shadows.json] [--images out/truth_shadows]

Per pixel of the ground the clouds do not hide, its light with the clouds over its light without them: in the
truth (`cloudview truth --terrain`'s path tracing, the scene with its clouds and without) and in the GL frame
(full 3D, the clouds' shadows on, no aerial perspective: the truth has no air), seen from `VIEW`, above the
valley's south end looking down across it.  The ground compared is where the truth's central ray meets the
terrain with the clouds' opacity along it under `CLEAR_ALPHA`.  Reports the share of that ground in shadow (a
factor under `SHADOW_FACTOR`) in each, the two shadows' intersection over union, the distance between their
centroids in pixels, each's mean factor over the truth's shadow, and the factors' correlation; with --images,
the two factor maps side by side (black 0, white 1 and over; red where the truth's ray does not meet clear ground).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402
from cloudcore.maths.colour import srgb_decode  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.truth import render_truth  # noqa: E402
from cloudcore.model.scene import Camera  # noqa: E402
from cloudcore.model.settings import FULL_3D  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

#: above the default valley's south end, looking north and down across it: the sun of the afternoon from the left
VIEW = Camera((0.0, 5000.0, 3000.0), (500.0, 0.0, -500.0), 60.0)
#: the ground compared: the clouds' opacity along the truth's central ray to it under this
CLEAR_ALPHA = 0.02
#: a pixel of the ground is in shadow where its light with the clouds is under this share of its light without
SHADOW_FACTOR = 0.8


def factors(with_clouds: np.ndarray, without: np.ndarray) -> np.ndarray:
    """(height, width): the luminance of linear `with_clouds` over that of `without` (0 where that is 0)."""
    weights = np.array([0.2126, 0.7152, 0.0722])
    lit, bare = with_clouds @ weights, without @ weights
    return np.divide(lit, bare, out=np.zeros_like(lit), where=bare > 1e-9)


def compare_shadows(truth_factor, gl_factor, ground) -> dict:
    """The two factor maps compared over the `ground` mask."""
    truth_shadow, gl_shadow = (ground & (f < SHADOW_FACTOR) for f in (truth_factor, gl_factor))
    union = np.count_nonzero(truth_shadow | gl_shadow)
    rows, columns = np.indices(ground.shape)

    def centroid(mask):
        return np.array([rows[mask].mean(), columns[mask].mean()]) if mask.any() else np.full(2, np.nan)

    return {
        "ground_pixels": int(np.count_nonzero(ground)),
        "truth_shadow_share": float(np.count_nonzero(truth_shadow) / max(np.count_nonzero(ground), 1)),
        "gl_shadow_share": float(np.count_nonzero(gl_shadow) / max(np.count_nonzero(ground), 1)),
        "intersection_over_union": float(np.count_nonzero(truth_shadow & gl_shadow) / union) if union else 1.0,
        "centroid_offset_px": float(np.linalg.norm(centroid(truth_shadow) - centroid(gl_shadow))),
        "truth_mean_factor_in_truth_shadow": float(truth_factor[truth_shadow].mean()) if truth_shadow.any() else 1.0,
        "gl_mean_factor_in_truth_shadow": float(gl_factor[truth_shadow].mean()) if truth_shadow.any() else 1.0,
        "truth_mean_factor_outside": float(truth_factor[ground & ~truth_shadow].mean()),
        "gl_mean_factor_outside": float(gl_factor[ground & ~truth_shadow].mean()),
        "correlation": float(np.corrcoef(truth_factor[ground], gl_factor[ground])[0, 1]),
    }


def factor_picture(truth_factor, gl_factor, ground) -> np.ndarray:
    """(height, 2 width + 4, 3) uint8: the truth's factors, a gap, the GL frame's; red off the compared ground."""
    panels = []
    for factor in (truth_factor, gl_factor):
        grey = np.clip(factor, 0.0, 1.0)[..., None] * np.ones(3)
        grey[~ground] = (0.6, 0.0, 0.0)
        panels.append(np.round(255 * grey).astype(np.uint8))
    gap = np.zeros((ground.shape[0], 4, 3), dtype=np.uint8)
    return np.concatenate([panels[0], gap, panels[1]], axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--size", default="160x120")
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--time-of-day", type=float, default=15.5)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--images", type=Path)
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    scene = load_scene(args.scene)
    scene = dataclasses.replace(scene, lighting=dataclasses.replace(scene.lighting, time_of_day=args.time_of_day))
    bare = dataclasses.replace(scene, clouds=())
    truths = [render_truth(s, width, height, camera=VIEW, spp=args.spp, terrain=True) for s in (scene, bare)]
    settings = dataclasses.replace(FULL_3D, aerial_perspective=False)
    with FrameRenderer(width, height) as renderer:
        frames = [srgb_decode(renderer.render(s, camera=VIEW, settings=settings)[0] / 255.0) for s in (scene, bare)]
    ground = np.isfinite(truths[0].ground_distance) & (truths[0].alpha < CLEAR_ALPHA)
    truth_factor, gl_factor = factors(truths[0].linear, truths[1].linear), factors(*frames)
    report = {
        "machine": machine(),
        "scene": str(args.scene),
        "size": args.size,
        "spp": args.spp,
        "time_of_day": args.time_of_day,
        "truth_seconds": [t.seconds for t in truths],
        **compare_shadows(truth_factor, gl_factor, ground),
    }
    if args.images is not None:
        import imageio.v3 as iio

        args.images.mkdir(parents=True, exist_ok=True)
        iio.imwrite(args.images / "factors.png", factor_picture(truth_factor, gl_factor, ground))
    write_report(report, args.json)


if __name__ == "__main__":
    main()
