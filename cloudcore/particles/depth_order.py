"""Far-to-near order of particles by distance, in linear time.

Splats blend back to front, so every draw sorts its particles by distance
from the eye, up to a hundred thousand of them each frame.  A comparison
sort of float64 keys costs several milliseconds there; a least-significant-
digit radix sort of the distances' float32 bit patterns (two stable passes
over 16-bit digits, which numpy runs as counting sorts) orders them exactly
as float32 in a fraction of that.  Positive IEEE floats order like their
bit patterns read as unsigned integers, and inverting the bits turns
ascending into descending.
"""

from __future__ import annotations

import numpy as np


def far_to_near(distances: np.ndarray) -> np.ndarray:
    """Indices that order `distances` (finite, >= 0) from the largest to the smallest.

    Equal distances (at float32 precision) keep their input order.
    """
    keys = distance_keys(distances)
    by_low = np.argsort((keys & 0xFFFF).astype(np.uint16), kind="stable")
    return by_low[np.argsort((keys[by_low] >> 16).astype(np.uint16), kind="stable")]


def distance_keys(distances: np.ndarray) -> np.ndarray:
    """(n,) uint32 keys that order `distances` (finite, >= 0) far to near when sorted ascending.

    Positive IEEE floats order like their bit patterns read as unsigned integers; inverting the bits turns
    ascending into descending.
    """
    return ~np.asarray(distances, dtype=np.float32).view(np.uint32)
