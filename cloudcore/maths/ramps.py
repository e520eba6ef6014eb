"""Smooth ramps shared by lighting (sun fades, golden hour) and rendering (near-eye particle fade)."""

from __future__ import annotations

import numpy as np


def smoothstep(edge0, edge1, x):
    """0 below edge0, 1 above edge1, a C1 Hermite ramp between; scalars or arrays, float64."""
    t = np.clip((np.asarray(x, dtype=np.float64) - edge0) / (np.asarray(edge1) - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)
