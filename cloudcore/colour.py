"""Colour management, stated once: all maths in linear RGB; one sRGB transfer (IEC 61966-2-1) to 8 bits.

shaders/world.frag.glsl has the decoding side in GLSL.
"""

from __future__ import annotations

import numpy as np


def srgb_encode(linear) -> np.ndarray:
    """Linear [0, 1] to sRGB-encoded [0, 1]; the input is clamped to [0, 1] first (NaN to 0)."""
    c = np.clip(np.nan_to_num(np.asarray(linear, dtype=np.float64), nan=0.0), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def linear_to_srgb8(linear) -> np.ndarray:
    """Linear colour to 8-bit sRGB, after clamping to [0, 1]."""
    return np.rint(srgb_encode(linear) * 255.0).astype(np.uint8)
