"""Unit vectors that stay finite: shared by the artist shading model and the sprite facing lock."""

from __future__ import annotations

import numpy as np


def unit_rows(vectors) -> np.ndarray:
    """Rows (..., 3) scaled to length 1; zero rows stay zero.

    Each row is divided by its largest component first, so no finite vector
    overflows or underflows on the way to its length.
    """
    vectors = np.asarray(vectors, dtype=np.float64)
    largest = np.abs(vectors).max(axis=-1, keepdims=True)
    scaled = np.divide(vectors, largest, out=np.zeros_like(vectors), where=largest > 0.0)
    length = np.linalg.norm(scaled, axis=-1, keepdims=True)
    return np.divide(scaled, length, out=np.zeros_like(scaled), where=length > 0.0)
