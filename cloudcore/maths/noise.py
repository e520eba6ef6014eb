"""Deterministic noise from an integer hash: the same values on every numpy version and platform.

A random generator's streams may change between numpy releases; an integer
hash cannot, so terrain, sprite textures and per-sprite choices built on it
never move under a golden image or a shipped file.
"""

from __future__ import annotations

import numpy as np


def hash01(ix: np.ndarray, iz: np.ndarray, seed: int) -> np.ndarray:
    """A value in [0, 1) per integer pair (ix, iz) (splitmix-style integer mixing)."""
    with np.errstate(over="ignore"):  # the mixing wraps modulo 2^64 on purpose
        h = (
            np.asarray(ix).astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
            ^ np.asarray(iz).astype(np.uint64) * np.uint64(0xC2B2AE3D27D4EB4F)
            ^ np.uint64(seed) * np.uint64(0x165667B19E3779F9)
        )
        h ^= h >> np.uint64(31)
        h *= np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(29)
    return (h >> np.uint64(11)).astype(np.float64) / float(1 << 53)


def value_noise(x: np.ndarray, z: np.ndarray, seed: int) -> np.ndarray:
    """Smoothly interpolated lattice noise in [-1, 1]."""
    x0, z0 = np.floor(x), np.floor(z)
    fx, fz = x - x0, z - z0
    sx, sz = fx * fx * (3 - 2 * fx), fz * fz * (3 - 2 * fz)
    ix, iz = x0.astype(np.int64), z0.astype(np.int64)
    with np.errstate(over="ignore"):  # ix + 1 wraps at the int64 limit: still a lattice point
        c00, c10 = hash01(ix, iz, seed), hash01(ix + 1, iz, seed)
        c01, c11 = hash01(ix, iz + 1, seed), hash01(ix + 1, iz + 1, seed)
    top = c00 + (c10 - c00) * sx
    bottom = c01 + (c11 - c01) * sx
    return 2.0 * (top + (bottom - top) * sz) - 1.0
