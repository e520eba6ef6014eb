"""Rows of vectors: their lengths, and unit vectors that stay finite (the artist shading model, the sprite facing
lock)."""

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


def row_lengths(vectors: np.ndarray) -> np.ndarray:
    """(N,): the lengths of the rows of `vectors` (N, 3), each the square root of its dot product with itself."""
    # half the time of np.linalg.norm(axis=1) (4,000 rows: 42 against 83 us): the planner measures every near
    # cloud's particles from the eye each frame, the renderer every particle it draws
    return np.sqrt(np.einsum("ij,ij->i", vectors, vectors))
