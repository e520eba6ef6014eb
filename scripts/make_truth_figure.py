"""A figure for docs/shading.md: rows of truth | model | difference, from `cloudview truth` outputs.

    python scripts/make_truth_figure.py out/truth_noon out/truth_sunset --model exact --out docs/images/truth.png

Each folder holds `truth.png` (`cloudview truth --out DIR/truth.png`) and the model pictures of
`--model-images DIR`; one row per folder, the three pictures side by side with a 4-pixel white gap.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from cloudcore.imagecompare import load_rgb8

GAP = 4


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--model", default="exact", help="the shading method shown beside the truth")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()

    rows = []
    for folder in args.folders:
        pictures = [load_rgb8(folder / name) for name in ("truth.png", f"{args.model}.png", f"{args.model}_diff.png")]
        gap = np.full((pictures[0].shape[0], GAP, 3), 255, dtype=np.uint8)
        rows.append(np.concatenate([pictures[0], gap, pictures[1], gap, pictures[2]], axis=1))
    separator = np.full((GAP, rows[0].shape[1], 3), 255, dtype=np.uint8)
    figure = np.concatenate([part for row in rows for part in (row, separator)][:-1], axis=0)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(args.out, figure)
    print(f"wrote {args.out} ({figure.shape[1]}x{figure.shape[0]})")


if __name__ == "__main__":
    main()
