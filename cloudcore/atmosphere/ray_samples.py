"""Where a ray through the air is sampled: midpoints dense near its lowest point, where the air is densest.

A ray's altitude is lowest at its start (rising rays) or where it passes closest to the ground (rays that
dip, from high up), and the densities fall off exponentially from there (Mie's over 1.2 km, a hundredth of
a grazing ray's length).  The samples are shared between the two sides of that point in proportion to
their lengths (a side of some length gets one at least), and on each side spaced quadratically away from
it (t = length * x^2 at the midpoints of x, as Hillaire's variable sample count places them): the midpoint
rule in x, so a rising ray spends every sample above its start.
"""

from __future__ import annotations

import numpy as np


def ray_samples(r, mu, distance, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(t, dt), each (..., samples) increasing along the ray: the sample positions and their step lengths
    (summing to `distance`) for rays from radius `r` (...) at cosine `mu` (...) over `distance` (...)."""
    r, mu, distance = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (r, mu, distance)))
    lowest = np.clip(-r * mu, 0.0, distance)[..., None]
    after_length = distance[..., None] - lowest
    share = np.divide(lowest, distance[..., None], out=np.zeros_like(lowest), where=distance[..., None] > 0.0)
    before = np.clip(
        np.rint(samples * share), np.where(lowest > 0.0, 1, 0), np.where(after_length > 0.0, samples - 1, samples)
    )
    after = np.maximum(samples - before, 1)
    index = np.arange(samples) + 0.5
    on_before = index < before
    # x in (0, 1) on the sample's side, counted away from the lowest point, and the side's step in x
    x = np.where(on_before, (before - index) / np.maximum(before, 1), (index - before) / after)
    dx = np.where(on_before, 1.0 / np.maximum(before, 1), 1.0 / after)
    side_length = np.where(on_before, lowest, after_length)
    t = np.where(on_before, lowest - lowest * x * x, lowest + after_length * x * x)
    # the step's length: its share of the side, (x + dx/2)^2 - (x - dx/2)^2 = 2 x dx
    return t, side_length * 2.0 * x * dx
