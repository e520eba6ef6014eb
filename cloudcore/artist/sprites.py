"""The cloud sprite atlas and which sprite each particle draws (Wang 2004, section 3.2).

Wang mixes 16 textures on one sheet to make a dozen cloud types: a
flat-bottomed one for cumulus bases, foggy ones "used heavily in stratus",
puffy ones for cumulus and wispy ones "used across all cloud types".  Here the
sheet is `cloudcore/resources/sprites/atlas.png`, ATLAS_GRID x ATLAS_GRID cells of
CELL_PIXELS, one kind per row (`ROWS`, top row first), four variants across;
`scripts/make_sprite_atlas.py` draws it (`cloudcore.artist.sprite_art`).

Channels: alpha is the sprite's opacity (its density mask); RGB is a
brightness texture that multiplies the shaded colour (Wang's final colour is
shading x texture colour x formation alpha, section 5.3).  Each sprite is
upright in its cell: its top toward the top of the image, a flat bottom's
edge toward the bottom.  Alpha is exactly 0 in each cell's outer
CELL_MARGIN_PIXELS, so mip levels 0 to ATLAS_MAX_MIP_LEVEL never mix two
sprites.

A cloud that draws sprites from the sheet has a `SpriteStyle`; one without
keeps the Gaussian splat.  Each particle gets a cell and a rotation within
the style's range (Wang: "a random rotation within the range"), from a hash
of (seed, particle index), so adding a particle never reshuffles the others.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from cloudcore.artist.artist_shading import height_fractions
from cloudcore.maths.noise import hash01
from cloudcore.model.cloud_records import ATLAS_GRID, FLAT_BOTTOM, SpriteStyle
from cloudcore.resources import ATLAS

ATLAS_PATH = ATLAS
CELL_PIXELS = 256
#: empty border of each cell, in pixels at mip level 0
CELL_MARGIN_PIXELS = 16
#: the deepest mip level at which cells still keep an empty border (16 px -> 1 px): clamp the texture's levels here
ATLAS_MAX_MIP_LEVEL = int(math.log2(CELL_MARGIN_PIXELS))


def sprite_choices(style: SpriteStyle, count: int, heights_fraction=None) -> tuple[np.ndarray, np.ndarray]:
    """Each particle's atlas cell (int32, row * ATLAS_GRID + column) and rotation (float64 radians), (count,).

    Particle i's choice depends only on (style, i) and, with a flat bottom, on
    its own height: the same for any `count` and on any machine.
    `heights_fraction` (count,), 0 at the cloud's bottom and 1 at its top
    (`cloudcore.artist.artist_shading.height_fractions`), is needed only when
    `style.flat_bottom_fraction` > 0.
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
        raise ValueError(f"count must be an integer >= 0, got {count!r}")
    index = np.arange(count, dtype=np.int64)

    def uniform(stream: int) -> np.ndarray:
        """Particle i's number of this stream, in [0, 1)."""
        return hash01(index, np.int64(stream), style.seed)

    rows = np.asarray(style.rows, dtype=np.int64)[(uniform(0) * len(style.rows)).astype(np.int64)]
    columns = (uniform(1) * ATLAS_GRID).astype(np.int64)
    spin = uniform(2)
    low, high = np.radians(style.rotation_deg)
    rotations = low + spin * (high - low)
    if style.flat_bottom_fraction > 0.0:
        if heights_fraction is None:
            raise ValueError("a style with a flat bottom needs each particle's height fraction")
        heights = np.asarray(heights_fraction, dtype=np.float64)
        if heights.shape != (count,):
            raise ValueError(f"heights_fraction must have shape ({count},), got {heights.shape}")
        bottom = heights <= style.flat_bottom_fraction
        rows = np.where(bottom, FLAT_BOTTOM, rows)
        bottom_low, bottom_high = np.radians(style.flat_bottom_rotation_deg)
        rotations = np.where(bottom, bottom_low + spin * (bottom_high - bottom_low), rotations)
    return (rows * ATLAS_GRID + columns).astype(np.int32), rotations


def particle_sprites(style: SpriteStyle, centres) -> tuple[np.ndarray, np.ndarray]:
    """`sprite_choices` for a cloud's particle centres (n, 3), heights measured over the centres'
    vertical extent (the same extent `cloudcore.artist.artist_shading.artist_colours` is given)."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    y = centres[:, 1]
    heights = height_fractions(y, float(y.min()), float(y.max())) if len(y) else np.zeros(0)
    return sprite_choices(style, len(centres), heights)


def atlas_cell_uv(index: int) -> tuple[float, float, float, float]:
    """Texture coordinates (u0, v0, u1, v1) of atlas cell `index` (row * ATLAS_GRID + column).

    u runs left to right; v runs from the top image row (v = 0) down, which is
    the GL t coordinate when `load_atlas()`'s array is uploaded as it is
    (array row 0 first).  So v0 < v1 and v0 is the cell's top edge: a quad
    corner at the sprite's upper left takes (u0, v0), its lower right (u1, v1).
    """
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < ATLAS_GRID**2:
        raise ValueError(f"atlas cell index must be an integer in [0, {ATLAS_GRID**2 - 1}], got {index!r}")
    row, column = divmod(int(index), ATLAS_GRID)
    return column / ATLAS_GRID, row / ATLAS_GRID, (column + 1) / ATLAS_GRID, (row + 1) / ATLAS_GRID


@functools.cache
def load_atlas() -> np.ndarray:
    """The sheet as (H, W, 4) float32 RGBA in [0, 1], rows top first (read-only, read once)."""
    import imageio.v3 as iio

    pixels = iio.imread(ATLAS_PATH)
    side = ATLAS_GRID * CELL_PIXELS
    if pixels.shape != (side, side, 4) or pixels.dtype != np.uint8:
        raise ValueError(
            f"{ATLAS_PATH}: expected {side}x{side} RGBA 8-bit, got {pixels.shape} {pixels.dtype}; "
            "regenerate it with scripts/make_sprite_atlas.py"
        )
    atlas = pixels.astype(np.float32) / np.float32(255.0)
    atlas.flags.writeable = False
    return atlas
