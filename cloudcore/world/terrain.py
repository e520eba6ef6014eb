"""Heightfield terrain: a procedural valley with noisy ridges between mountains, deterministic from a seed, or a
heightmap's samples; and the ground's colour by height and slope.

Noise comes from an integer hash (`cloudcore.maths.noise`), not a random generator,
so the same parameters give the same heights on every numpy version and platform.
A heightmap is sampled bilinearly, its edge samples held beyond the patch it covers.
"""

from __future__ import annotations

import numpy as np

from cloudcore.maths.noise import value_noise
from cloudcore.model.scene import Terrain

_OCTAVES = 6
#: the mountains' octaves, their largest wavelength (m) and where they rise, in the valley's half-widths from
#: its axis: from just inside its side (the clouds hang over the floor) to their full height a half-width out
_MOUNTAIN_OCTAVES = 5
_MOUNTAIN_WAVELENGTH_M = 5000.0
_MOUNTAINS_RISE = (0.85, 2.0)


def height_at(terrain: Terrain, x, z) -> np.ndarray:
    """Terrain height (metres) at world (x, z): the heightmap's where the terrain has one, else the procedural
    valley's, which runs along z; the mountains of `relief` beyond the patch's sides either way."""
    x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
    half_x = 0.5 * terrain.size[0]
    if terrain.heights is not None:
        heights = terrain.height * _bilinear(
            terrain.heights.values, x / terrain.size[0] + 0.5, z / terrain.size[1] + 0.5
        )
    else:
        heights = _valley(terrain, x, z)
    if terrain.relief > 0.0:
        heights = heights + terrain.relief * _mountains(terrain.seed, x, z, np.abs(x) / half_x)
    return heights


def _bilinear(grid: np.ndarray, u, v) -> np.ndarray:
    """`grid` (rows along v, columns along u) at (u, v) in [0, 1]^2 over its samples, bilinearly; clamped
    outside."""
    rows, columns = grid.shape
    fx = np.clip(u, 0.0, 1.0) * (columns - 1)
    fz = np.clip(v, 0.0, 1.0) * (rows - 1)
    i = np.minimum(fx.astype(np.int64), columns - 2)
    j = np.minimum(fz.astype(np.int64), rows - 2)
    sx, sz = fx - i, fz - j
    top = grid[j, i] * (1.0 - sx) + grid[j, i + 1] * sx
    bottom = grid[j + 1, i] * (1.0 - sx) + grid[j + 1, i + 1] * sx
    return top * (1.0 - sz) + bottom * sz


def _valley(terrain: Terrain, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The procedural valley's heights (metres), without the mountains."""
    half_x = 0.5 * terrain.size[0]
    across = np.clip(np.abs(x) / half_x, 0.0, 1.0)
    valley = across**1.6
    wavelength = 0.35 * min(terrain.size)
    noise = np.zeros(np.broadcast(x, z).shape)
    amplitude, total = 1.0, 0.0
    for octave in range(_OCTAVES):
        noise += amplitude * value_noise(x / wavelength, z / wavelength, terrain.seed + 101 * octave)
        total += amplitude
        amplitude *= 0.5
        wavelength *= 0.5
    ridges = 0.55 + 0.45 * noise / total
    return terrain.height * (0.08 + 0.92 * valley * ridges) + 0.05 * terrain.height * noise / total


def highest_ground_m(terrain: Terrain) -> float:
    """A height no ground of `terrain` rises above: the heightmap's highest sample, or the valley's hills'
    1.05 `height`; and the mountains' relief."""
    hills = terrain.height * (terrain.heights.values.max() if terrain.heights is not None else 1.05)
    return float(hills) + terrain.relief


def lowest_ground_m(terrain: Terrain) -> float:
    """A height no ground of `terrain` falls below: the heightmap's lowest sample, else the valley's floor, 0 (its
    noise never takes it lower; the mountains only add)."""
    return float(terrain.height * terrain.heights.values.min()) if terrain.heights is not None else 0.0


def samples_across(terrain: Terrain) -> tuple[int, int]:
    """(along x, along z) samples of the heightfield over `size`: the heightmap's pixels, else `resolution`."""
    if terrain.heights is not None:
        rows, columns = terrain.heights.values.shape
        return columns, rows
    return terrain.resolution, terrain.resolution


def finest_cell_m(terrain: Terrain) -> float:
    """The heightfield's sample spacing in metres (the finer of its two)."""
    nx, nz = samples_across(terrain)
    return min(terrain.size[0] / (nx - 1), terrain.size[1] / (nz - 1))


def ground_colours(terrain: Terrain, positions: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(n, 3) linear RGB of the ground at `positions` with unit `normals`: `color_ramp` by height (its rows'
    colours interpolated, held past its ends) or else `color`, turned toward `steep_color` from the first of
    `steep_slope_deg` to the second."""
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    if terrain.color_ramp:
        ramp = np.array(terrain.color_ramp, dtype=np.float64)
        colours = np.stack([np.interp(positions[:, 1], ramp[:, 0], ramp[:, k]) for k in (1, 2, 3)], axis=1)
    else:
        colours = np.broadcast_to(np.asarray(terrain.color, dtype=np.float64), positions.shape).copy()
    if terrain.steep_color is not None:
        flat, steep = np.radians(terrain.steep_slope_deg)
        slope = np.arccos(np.clip(np.asarray(normals, dtype=np.float64).reshape(-1, 3)[:, 1], -1.0, 1.0))
        weight = np.clip((slope - flat) / (steep - flat), 0.0, 1.0)[:, None]
        colours = colours * (1.0 - weight) + np.asarray(terrain.steep_color, dtype=np.float64) * weight
    return colours


def _mountains(seed: int, x, z, across) -> np.ndarray:
    """In [0, 1]: ridged noise (sharp crests where the noise crosses zero) that rises from the valley's sides
    (`across`, in its half-widths from the axis) to mountains, Harris's figure 3."""
    low, high = _MOUNTAINS_RISE
    rise = np.clip((across - low) / (high - low), 0.0, 1.0)
    rise = rise * rise * (3.0 - 2.0 * rise)
    ridged = np.zeros(np.broadcast(x, z).shape)
    amplitude, total, wavelength = 1.0, 0.0, _MOUNTAIN_WAVELENGTH_M
    for octave in range(_MOUNTAIN_OCTAVES):
        ridged += amplitude * (1.0 - np.abs(value_noise(x / wavelength, z / wavelength, seed + 7919 + 101 * octave)))
        total += amplitude
        amplitude *= 0.5
        wavelength *= 0.5
    return rise * (0.3 + 0.7 * (ridged / total) ** 2)


def heightfield_mesh(terrain: Terrain) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (X*Z, 3) and triangles (2 (X-1) (Z-1), 3) of the heightfield at its samples
    (`samples_across`), centred on the origin."""
    n, rows = samples_across(terrain)
    xs = np.linspace(-0.5 * terrain.size[0], 0.5 * terrain.size[0], n)
    zs = np.linspace(-0.5 * terrain.size[1], 0.5 * terrain.size[1], rows)
    x, z = np.meshgrid(xs, zs)
    vertices = np.stack([x, height_at(terrain, x, z), z], axis=-1).reshape(-1, 3)
    corner = (np.arange(rows - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    # counter-clockwise seen from above (+y) so the faces point up
    first = np.stack([corner, corner + n, corner + 1], axis=1)
    second = np.stack([corner + 1, corner + n, corner + n + 1], axis=1)
    return vertices, np.concatenate([first, second]).astype(np.int64)
