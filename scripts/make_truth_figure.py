"""A figure for docs/shading.md: rows of truth | model | luminance difference | ..., from `cloudview truth` outputs.

    python scripts/make_truth_figure.py out/truth_noon out/truth_sunset --out docs/images/truth_vs_harris.png

Each folder holds `truth.png` (`cloudview truth --out DIR/truth.png`) and the model pictures of
`--model-images DIR`; one row per folder: the truth, then each of `--models` and its difference,
side by side with a 4-pixel white gap.
The difference is signed: red where the model is brighter than the truth, blue where it is darker,
full at a relative luminance difference of `--full-scale` (0.5), black where they agree.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.measure.imagecompare import load_rgb8
from cloudcore.measure.truth_comparison import luminance

GAP = 4


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument(
        "--models", default="harris-exact,saturated-exact", help="the models shown beside the truth (report names)"
    )
    parser.add_argument("--full-scale", type=float, default=0.5, help="luminance difference shown at full colour")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()

    rows = []
    for folder in args.folders:
        truth = load_rgb8(folder / "truth.png")
        pictures = [truth]
        for name in args.models.split(","):
            model = load_rgb8(folder / f"{name}.png")
            signed = (luminance(model) - luminance(truth)) / args.full_scale
            difference = np.zeros(truth.shape)
            difference[..., 0], difference[..., 2] = np.clip(signed, 0, 1), np.clip(-signed, 0, 1)
            pictures += [model, linear_to_srgb8(difference)]
        gap = np.full((truth.shape[0], GAP, 3), 255, dtype=np.uint8)
        rows.append(np.concatenate([part for picture in pictures for part in (picture, gap)][:-1], axis=1))
    separator = np.full((GAP, rows[0].shape[1], 3), 255, dtype=np.uint8)
    figure = np.concatenate([part for row in rows for part in (row, separator)][:-1], axis=0)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(args.out, figure)
    print(f"wrote {args.out} ({figure.shape[1]}x{figure.shape[0]})")


if __name__ == "__main__":
    main()
