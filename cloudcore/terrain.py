"""Procedural heightfield terrain: a valley with noisy ridges between mountains, deterministic from a seed.

Noise comes from an integer hash (`cloudcore.noise`), not a random generator,
so the same parameters give the same heights on every numpy version and platform.
"""

from __future__ import annotations

import numpy as np

from cloudcore.noise import value_noise
from cloudcore.scene import Terrain

_OCTAVES = 6
#: the mountains' octaves, their largest wavelength (m) and where they rise, in the valley's half-widths from
#: its axis: from just inside its side (the clouds hang over the floor) to their full height a half-width out
_MOUNTAIN_OCTAVES = 5
_MOUNTAIN_WAVELENGTH_M = 5000.0
_MOUNTAINS_RISE = (0.85, 2.0)


def height_at(terrain: Terrain, x, z) -> np.ndarray:
    """Terrain height (metres) at world (x, z); the valley runs along z."""
    x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
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
    heights = terrain.height * (0.08 + 0.92 * valley * ridges) + 0.05 * terrain.height * noise / total
    if terrain.relief > 0.0:
        heights = heights + terrain.relief * _mountains(terrain.seed, x, z, np.abs(x) / half_x)
    return heights


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
    """Vertices (R*R, 3) and triangles (2 (R-1)^2, 3) of the heightfield, centred on the origin."""
    n = terrain.resolution
    xs = np.linspace(-0.5 * terrain.size[0], 0.5 * terrain.size[0], n)
    zs = np.linspace(-0.5 * terrain.size[1], 0.5 * terrain.size[1], n)
    x, z = np.meshgrid(xs, zs)
    vertices = np.stack([x, height_at(terrain, x, z), z], axis=-1).reshape(-1, 3)
    i = np.arange(n - 1)
    corner = (i[:, None] * n + i[None, :]).ravel()
    # counter-clockwise seen from above (+y) so the faces point up
    first = np.stack([corner, corner + n, corner + 1], axis=1)
    second = np.stack([corner + 1, corner + n, corner + n + 1], axis=1)
    return vertices, np.concatenate([first, second]).astype(np.int64)
