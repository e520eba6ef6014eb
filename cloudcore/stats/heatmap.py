"""Overdraw counts as a colour image: a perceptual ramp from black through purple and orange to pale yellow (numpy).

The ramp is matplotlib's *inferno* sampled at nine points and interpolated
linearly: its lightness rises steadily, so more overdraw always reads as
brighter, in colour and in grey.  The scale runs from 0 to `legend_top`, the
highest count rounded up to a whole fragment, which the legend shows.
"""

from __future__ import annotations

import math

import numpy as np

#: inferno at 0, 1/8, ..., 1 (sRGB, 0-1)
RAMP = np.array(
    [
        [0.0015, 0.0005, 0.0139],
        [0.1293, 0.0473, 0.2908],
        [0.3415, 0.0623, 0.4294],
        [0.5409, 0.1347, 0.4151],
        [0.7357, 0.2159, 0.3302],
        [0.8943, 0.3534, 0.1936],
        [0.9784, 0.5579, 0.0349],
        [0.9746, 0.7977, 0.2063],
        [0.9884, 0.9984, 0.6449],
    ]
)


def ramp_colours(values) -> np.ndarray:
    """sRGB uint8 (..., 3) of `values` in [0, 1] (clipped) along the ramp."""
    values = np.clip(np.nan_to_num(np.asarray(values, dtype=np.float64)), 0.0, 1.0)
    position = values * (len(RAMP) - 1)
    low = np.minimum(position.astype(np.int64), len(RAMP) - 2)
    fraction = (position - low)[..., None]
    colours = RAMP[low] * (1.0 - fraction) + RAMP[low + 1] * fraction
    return np.rint(colours * 255.0).astype(np.uint8)


def legend_top(counts) -> float:
    """The count the ramp's top stands for: the highest count, rounded up to a whole fragment, at least 1."""
    highest = float(np.max(counts)) if np.size(counts) else 0.0
    return float(max(1, math.ceil(highest)))


def heat_image(counts, top: float | None = None) -> tuple[np.ndarray, float]:
    """(RGBA uint8 (height, width, 4), top): `counts` (height, width) coloured on the scale 0 to `top`
    (by default `legend_top(counts)`), opaque."""
    counts = np.asarray(counts, dtype=np.float64)
    top = legend_top(counts) if top is None else float(top)
    if not (math.isfinite(top) and top > 0.0):
        raise ValueError(f"the top of the heat scale must be finite and > 0, got {top}")
    rgb = ramp_colours(counts / top)
    return np.concatenate([rgb, np.full((*counts.shape, 1), 255, dtype=np.uint8)], axis=-1), top
