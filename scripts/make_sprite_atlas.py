"""Regenerate the cloud sprite atlas cloudcore/resources/sprites/atlas.png (Wang 2004, section 3.2, figure 6).

    python scripts/make_sprite_atlas.py [--out cloudcore/resources/sprites/atlas.png] [--seed 2004]

A 4x4 sheet of 256 px cells, one kind per row from the top: flat-bottom,
foggy, puffy, wispy (`cloudcore.model.cloud_records.ROWS`), four variants each, drawn
from hashed noise by `cloudcore.artist.sprite_art`: the same file on every machine.
RGBA, 8 bits: alpha is opacity, RGB brightness.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from cloudcore.artist.sprite_art import ATLAS_SEED, render_atlas
from cloudcore.artist.sprites import ATLAS_PATH


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ATLAS_PATH)
    parser.add_argument("--seed", type=int, default=ATLAS_SEED)
    arguments = parser.parse_args()
    pixels = np.rint(render_atlas(arguments.seed) * 255.0).astype(np.uint8)
    arguments.out.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(arguments.out, pixels, extension=".png", optimize=True)
    print(f"wrote {arguments.out} ({arguments.out.stat().st_size:,} bytes)")


if __name__ == "__main__":
    main()
