"""Procedural cloud sprite textures for the atlas (Wang 2004, section 3.2): flat-bottom, foggy, puffy, wispy.

Wang's artists painted 16 textures "with interesting features that resemble
eddies and wisps" so that few sprites make a detailed cloud.  These are drawn
from hashed value noise (`cloudcore.maths.noise`), four variants per kind, so the
sheet is the same on every machine and `scripts/make_sprite_atlas.py`
regenerates `cloudcore/resources/sprites/atlas.png` exactly.

Each cell holds one sprite, upright: its top toward the top of the image.
Alpha is the sprite's opacity; RGB its brightness (grey, except the foggy
row's "subtle bluish-grey tinge").  Alpha reaches exactly 0 at
`SPRITE_EXTENT` of the half cell, so the cell's outer `CELL_MARGIN_PIXELS`
stay empty and neither bilinear filtering nor the first mip levels mix
neighbouring sprites.  Brightness is defined over the whole cell, with no
black outside the sprite, so filtering opacity to zero never darkens the rim.
"""

from __future__ import annotations

import numpy as np

from cloudcore.artist.sprites import CELL_MARGIN_PIXELS, CELL_PIXELS
from cloudcore.maths.noise import hash01, value_noise
from cloudcore.maths.ramps import smoothstep
from cloudcore.model.cloud_records import ATLAS_GRID, FLAT_BOTTOM, FOGGY, PUFFY, WISPY

ATLAS_SEED = 2004
#: where alpha has reached 0, as a fraction of the half cell: the margin starts there
SPRITE_EXTENT = 1.0 - CELL_MARGIN_PIXELS / (0.5 * CELL_PIXELS)
#: height of a flat bottom, as a fraction of the half cell below the centre
FLAT_BOTTOM_Y = -0.42
#: the foggy textures' tint (Wang: "a subtle bluish-grey tinge")
FOGGY_TINT = np.array([0.92, 0.95, 1.0])


def render_atlas(seed: int = ATLAS_SEED) -> np.ndarray:
    """The whole sheet, (ATLAS_GRID * CELL_PIXELS,) * 2 + (4,) RGBA float64 in [0, 1], rows top first.

    Atlas row r (top to bottom) holds kind r of `cloudcore.model.cloud_records.ROWS`, four variants across.
    """
    kinds = {FLAT_BOTTOM: _flat_bottom, FOGGY: _foggy, PUFFY: _puffy, WISPY: _wispy}
    rows = []
    for row in range(ATLAS_GRID):
        cells = [_cell(kinds[row], seed, row * ATLAS_GRID + column) for column in range(ATLAS_GRID)]
        rows.append(np.concatenate(cells, axis=1))
    return np.concatenate(rows, axis=0)


def _cell(kind, seed: int, index: int) -> np.ndarray:
    """One sprite: (CELL_PIXELS, CELL_PIXELS, 4), x right and y up in [-1, 1] over the cell."""
    centres = (np.arange(CELL_PIXELS) + 0.5) / CELL_PIXELS * 2.0 - 1.0
    x, y = np.meshgrid(centres, -centres)  # image rows run downward, y upward

    def parameter(k: int) -> float:
        """The k-th random number of this cell, in [0, 1)."""
        return float(hash01(np.int64(index), np.int64(k), seed))

    alpha, brightness, tint = kind(x, y, parameter, seed * 97 + index * 7919)
    window = 1.0 - smoothstep(SPRITE_EXTENT - 0.15, SPRITE_EXTENT, np.hypot(x, y))
    rgb = np.clip(brightness, 0.0, 1.0)[..., None] * tint
    return np.dstack([rgb, np.clip(alpha, 0.0, 1.0) * window])


def _fbm(x, y, seed: int, frequency: float, octaves: int = 4) -> np.ndarray:
    """Fractal value noise in [-1, 1]: octaves of halving amplitude and doubling frequency."""
    total, amplitude, norm = np.zeros_like(x), 1.0, 0.0
    for octave in range(octaves):
        total += amplitude * value_noise(x * frequency, y * frequency, seed + 101 * octave)
        norm += amplitude
        amplitude *= 0.5
        frequency *= 2.0
    return total / norm


def _blobs(x, y, parameter, count: int, first: int, spread, height, radius) -> np.ndarray:
    """Soft union in [0, 1] of `count` round blobs; spread, height and radius are (low, high) ranges."""
    empty = np.ones_like(x)
    for blob in range(count):
        k = first + 4 * blob
        bx = spread[0] + parameter(k) * (spread[1] - spread[0])
        by = height[0] + parameter(k + 1) * (height[1] - height[0])
        r = radius[0] + parameter(k + 2) * (radius[1] - radius[0])
        inside = np.clip(1.0 - ((x - bx) ** 2 + (y - by) ** 2) / (r * r), 0.0, 1.0)
        empty *= 1.0 - inside
    return 1.0 - empty


def _flat_bottom(x, y, parameter, seed):
    """A cumulus cap on a straight horizontal base: Wang's texture for cumulus bottoms."""
    billow = _fbm(x, y, seed, 5.0)
    # blobs reach below the base line so it cuts a long straight edge
    body = _blobs(x, y / (1.0 + 0.12 * billow), parameter, 5, 0, (-0.38, 0.38), (-0.38, 0.12), (0.26, 0.4))
    body = np.maximum(body, _blobs(x, y, parameter, 2, 40, (-0.28, 0.28), (-0.45, -0.35), (0.32, 0.42)))
    alpha = smoothstep(0.02, 0.6, body) * smoothstep(FLAT_BOTTOM_Y, FLAT_BOTTOM_Y + 0.025, y)
    # lit from above: the base is a little darker, creases darker still
    brightness = 0.76 + 0.2 * smoothstep(FLAT_BOTTOM_Y, 0.5, y) + 0.08 * billow
    return alpha, brightness, np.ones(3)


def _foggy(x, y, parameter, seed):
    """A wide, soft, thin veil: Wang's stratus texture."""
    wide = 0.7 + 0.1 * parameter(0)
    low = _fbm(x, y, seed, 2.5, octaves=3)
    distance = np.hypot(x / wide, y / (0.45 + 0.1 * parameter(1))) * (1.0 + 0.18 * low)
    alpha = (
        (0.55 + 0.1 * parameter(2)) * (1.0 - smoothstep(0.15, 1.0, distance)) * (0.8 + 0.2 * _fbm(x, y, seed + 7, 6.0))
    )
    brightness = 0.9 + 0.06 * low
    return alpha, brightness, FOGGY_TINT


def _puffy(x, y, parameter, seed):
    """A cauliflower cluster of rounded puffs: Wang's cumulus detail."""
    billow = np.abs(_fbm(x, y, seed, 6.0))  # creases where the noise crosses zero
    body = _blobs(
        x * (1.0 + 0.15 * billow), y * (1.0 + 0.15 * billow), parameter, 6, 0, (-0.35, 0.35), (-0.3, 0.3), (0.22, 0.4)
    )
    alpha = smoothstep(0.02, 0.55, body) * (0.85 + 0.15 * billow)
    brightness = 0.7 + 0.18 * smoothstep(-0.6, 0.6, y) + 0.22 * billow
    return alpha, brightness, np.ones(3)


def _wispy(x, y, parameter, seed):
    """Two or three curved, fibrous streaks: Wang's wisps, used across cloud types."""
    alpha = np.zeros_like(x)
    for strand in range(2 + int(parameter(0) * 2)):
        k = 1 + 5 * strand
        angle = np.pi * (parameter(k) - 0.5) * 0.6  # streaks lie roughly across the sprite
        along = np.cos(angle) * x + np.sin(angle) * y
        across = -np.sin(angle) * x + np.cos(angle) * y - (parameter(k + 1) - 0.5) * 0.5
        across -= (parameter(k + 2) - 0.5) * 0.8 * along * along  # a bend
        width = 0.08 + 0.1 * parameter(k + 3)
        fibres = 1.0 - np.abs(value_noise(along * 3.0, across * 22.0, seed + strand))  # thin lines along the streak
        profile = (1.0 - smoothstep(0.0, width, np.abs(across))) * (1.0 - smoothstep(0.25, 0.75, np.abs(along)))
        alpha = np.maximum(alpha, profile * (0.35 + 0.45 * fibres**2))
    brightness = 0.9 + 0.08 * _fbm(x, y, seed, 4.0, octaves=3)
    return alpha * (0.75 + 0.25 * parameter(20)), brightness, np.ones(3)
