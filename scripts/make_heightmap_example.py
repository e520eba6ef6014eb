"""Write the example heightmap: the default scene's procedural valley (its hills, not its mountains) as a
257x257 16-bit greyscale PNG, the heights of cloudcore/resources/scenes/heightmap_valley.toml.

    python scripts/make_heightmap_example.py [--out cloudcore/resources/scenes/heightmap_valley.png]

The image covers the valley's 6 km patch, its top row at -z; white is the patch's highest ground, which the
scene's `height` restores in metres (printed).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from cloudcore.resources import DEFAULT_SCENE, resource_path
from cloudcore.scenes.files import load_scene
from cloudcore.scenes.interop.heightmap import write_heightmap
from cloudcore.world.terrain import height_at

SAMPLES = 257

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=resource_path("scenes", "heightmap_valley.png"))
    args = parser.parse_args()
    valley = dataclasses.replace(load_scene(DEFAULT_SCENE).terrain, relief=0.0)
    x, z = np.meshgrid(*(np.linspace(-0.5 * side, 0.5 * side, SAMPLES) for side in valley.size))
    heights = height_at(valley, x, z)
    write_heightmap(args.out, heights / heights.max())
    print(f"wrote {args.out}: {SAMPLES}x{SAMPLES}, white = {heights.max():.2f} m")
