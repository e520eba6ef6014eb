"""Tables read as a GPU's linear, clamp-to-edge sampler reads a texture, so the numpy side and the shaders agree.

A table is (height, width, channels); u runs along the width, v along the height, texel i's centre at
(i + 0.5) / size.  `texel_centres` gives the coordinates a table is built at; Hillaire's sub-uv helpers
(`fromUnitToSubUvs`, `fromSubUvsToUnit`) stretch a parameter's [0, 1] onto the first to the last centre,
so that its ends are texels rather than clamped halves of one.
"""

from __future__ import annotations

import numpy as np


def texel_centres(size: int) -> np.ndarray:
    return (np.arange(size) + 0.5) / size


def unit_to_sub_uv(u, size: int) -> np.ndarray:
    return (np.asarray(u, dtype=np.float64) + 0.5 / size) * (size / (size + 1.0))


def sub_uv_to_unit(u, size: int) -> np.ndarray:
    return (np.asarray(u, dtype=np.float64) - 0.5 / size) * (size / (size - 1.0))


def sample_bilinear(table: np.ndarray, u, v) -> np.ndarray:
    """(..., channels): `table` (height, width, channels) at (u, v) (...), bilinear, clamped to the edge texels."""
    height, width, channels = table.shape
    u, v = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
    x = np.clip(np.nan_to_num(u) * width - 0.5, 0.0, width - 1.0)
    y = np.clip(np.nan_to_num(v) * height - 0.5, 0.0, height - 1.0)
    x0 = np.minimum(x.astype(np.int64), max(width - 2, 0))
    y0 = np.minimum(y.astype(np.int64), max(height - 2, 0))
    fx, fy = (x - x0).ravel(), (y - y0).ravel()
    step_x, step_y = min(width - 1, 1), width * min(height - 1, 1)
    corner = (y0 * width + x0).ravel()
    flat = table.reshape(-1, channels)
    weights = ((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy)
    # one flat gather per corner: a quarter of the time of indexing by row and column
    result = sum(
        np.take(flat, corner + offset, axis=0) * weight[:, None]
        for offset, weight in zip((0, step_x, step_y, step_x + step_y), weights, strict=True)
    )
    return result.reshape(*x.shape, channels)


def sample_trilinear(volume: np.ndarray, u, v, w) -> np.ndarray:
    """(..., channels): `volume` (depth, height, width, channels) at (u, v, w) (...), trilinear, clamped to the
    edge texels as a GPU samples a 3D texture: the two slices around w bilinear, then mixed."""
    depth = volume.shape[0]
    z = np.clip(np.nan_to_num(np.asarray(w, dtype=np.float64)) * depth - 0.5, 0.0, depth - 1.0)
    z0 = np.minimum(z.astype(np.int64), max(depth - 2, 0))
    fz = (z - z0)[..., None]
    z1 = np.minimum(z0 + 1, depth - 1)
    # the slices as one table of stacked rows: slice k's row y is row k * height + y
    height = volume.shape[1]
    stacked = volume.reshape(depth * height, *volume.shape[2:])
    v = np.clip(np.nan_to_num(np.asarray(v, dtype=np.float64)), 0.5 / height, 1.0 - 0.5 / height)
    near = sample_bilinear(stacked, u, (z0 * height + v * height) / (depth * height))
    far = sample_bilinear(stacked, u, (z1 * height + v * height) / (depth * height))
    return (1.0 - fz) * near + fz * far
