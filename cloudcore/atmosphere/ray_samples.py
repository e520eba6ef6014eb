"""Where a ray through the air is sampled: midpoints dense near its lowest point, where the air is densest.

A ray's altitude is lowest at its start (rising rays) or where it passes closest to the ground (rays that
dip, from high up), and the densities fall off exponentially from there (Mie's over 1.2 km, a hundredth of
a grazing ray's length).  Each side of that point gets `steps` midpoints spaced quadratically away from
it (t = length * x^2, as Hillaire's variable sample count places them), so both halves of a grazing
ray are sampled where they matter and a rising ray's empty half has zero-length steps.
"""

from __future__ import annotations

import numpy as np


def ray_samples(r, mu, distance, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(t, dt), each (..., 2 * steps) increasing along the ray: the sample positions and their step lengths
    (summing to `distance`) for rays from radius `r` (...) at cosine `mu` (...) over `distance` (...)."""
    r, mu, distance = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (r, mu, distance)))
    lowest = np.clip(-r * mu, 0.0, distance)[..., None]
    edges = (np.arange(steps + 1) / steps) ** 2
    midpoints = ((np.arange(steps) + 0.5) / steps) ** 2
    widths = np.diff(edges)
    before = lowest - lowest * midpoints[::-1]
    after = lowest + (distance[..., None] - lowest) * midpoints
    t = np.concatenate([before, after], axis=-1)
    dt = np.concatenate([lowest * widths[::-1], (distance[..., None] - lowest) * widths], axis=-1)
    return t, dt
