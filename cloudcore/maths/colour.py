"""Colour management, stated once: all maths in linear RGB; one sRGB transfer (IEC 61966-2-1) to 8 bits."""

from __future__ import annotations

import numpy as np


def srgb_encode(linear) -> np.ndarray:
    """Linear [0, 1] to sRGB-encoded [0, 1]; the input is clamped to [0, 1] first (NaN to 0)."""
    c = np.clip(np.nan_to_num(np.asarray(linear, dtype=np.float64), nan=0.0), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded) -> np.ndarray:
    """sRGB-encoded [0, 1] to linear [0, 1] (the inverse of `srgb_encode`)."""
    c = np.clip(np.asarray(encoded, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


#: the 4x4 ordered-dither (Bayer) matrix: each pixel's rounding threshold is (entry + 0.5) / 16
BAYER_4 = np.array([[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]], dtype=np.float64)


#: the pixels `linear_to_srgb8` converts at once: its float64 temporaries of a whole 4096x4096 frame at once
#: took 1.4 GB, and `cloudview render`'s peak 125 bytes a pixel (now 32 on a plain scene)
CONVERTED_AT_ONCE = 1 << 20


def dither_thresholds(height: int, width: int, rows: slice = slice(None)) -> np.ndarray:
    """(height, width) rounding thresholds in (0, 1), or those of `rows` of them, indexed as GL's gl_FragCoord
    is: row 0 of the image (its top) is the frame's last row, so the editor's shader and this agree pixel for
    pixel."""
    pattern_rows = (height - 1 - np.arange(height)[rows]) % 4
    return (BAYER_4[pattern_rows][:, np.arange(width) % 4] + 0.5) / 16.0


def linear_to_srgb8(linear) -> np.ndarray:
    """Linear colour (height, width, channels; top row first) to 8-bit sRGB, after clamping to [0, 1].

    Dithered once, here at the 8-bit output (ordered, 4x4): a dark sky or a slow gradient spans
    only a few sRGB levels, and rounding every pixel the same way bands it; a per-pixel threshold
    keeps each 4x4 block's mean on the true value (within 1/32 of a level) for one level of noise.
    Values on a level stay exactly on it.  shaders/present.frag.glsl does the same for the editor.
    Converted a band of rows at a time, each pixel the same way: the memory is the output's and a band's.
    """
    linear = np.asarray(linear)
    height, width = linear.shape[:2]
    srgb = np.empty(linear.shape, dtype=np.uint8)
    band = max(1, CONVERTED_AT_ONCE // max(width, 1))
    for first in range(0, height, band):
        rows = slice(first, min(first + band, height))
        encoded = srgb_encode(linear[rows]) * 255.0
        thresholds = dither_thresholds(height, width, rows)
        if encoded.ndim == 3:
            thresholds = thresholds[:, :, None]
        srgb[rows] = np.clip(np.floor(encoded + thresholds), 0.0, 255.0)
    return srgb
