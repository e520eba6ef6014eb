"""The camera-centred nested grid of a cloud field: which cells each ring holds, and how levels blend.

Yusov (2014, section 5.2), after the geometry clipmaps of Losasso and Hoppe:
rectangular rings of cells centred on the camera, each ring's cells twice the
size of the ring inside it.  Level k's cells have the side
`cell_size * 2**k` and tile the field's plane from its centre, so a cell of
level k + 1 is exactly four of level k.  Distances are horizontal and
Chebyshev (max(|dx|, |dz|)): the rings are squares, as his figure 7.

Level k reaches `RING_HALF_CELLS` of its own cells from the eye.  Its outer
band, one of its cells wide, is where it fades out while level k + 1 fades in
over the same band (the grids overlap there), by weights that sum to one at
every point: `smoothstep(t)` and `1 - smoothstep(t)` of the same `t`.  The
weights are per particle and follow the eye continuously, and a cell is made
only while some point of it has a weight above zero, so a cell enters and
leaves at weight zero and nothing pops.  The last ring fades out the same
way, toward the horizon.  Pure numpy.
"""

from __future__ import annotations

import math

import numpy as np

from cloudcore.maths.ramps import smoothstep
from cloudcore.model.scene import CloudField

#: how many of its own cells a ring reaches from the eye (Chebyshev): each ring is 2 x 4 cells across, its
#: inner part under the finer rings; 4 leaves a solid band of one cell between the two blend bands
RING_HALF_CELLS = 4


def cell_side(field: CloudField, level: int) -> float:
    """Side in metres of a cell of `level` (0 the inner ring)."""
    return field.cell_size * 2.0**level


def level_reach(field: CloudField, level: int) -> float:
    """Chebyshev distance from the eye where `level` has faded out completely."""
    return RING_HALF_CELLS * cell_side(field, level)


def level_support(field: CloudField, level: int) -> tuple[float, float]:
    """(lo, hi): the level's weight is above zero for lo < distance < hi (lo is -inf for the inner ring)."""
    lo = -math.inf if level == 0 else level_reach(field, level - 1) - cell_side(field, level - 1)
    return lo, level_reach(field, level)


def chebyshev_distances(x, z, eye) -> np.ndarray:
    """Horizontal Chebyshev distances from `eye` (x, y, z) to the points (x, z)."""
    return np.maximum(
        np.abs(np.asarray(x, dtype=np.float64) - eye[0]), np.abs(np.asarray(z, dtype=np.float64) - eye[2])
    )


def level_weights(field: CloudField, levels: np.ndarray, x, z, eye) -> np.ndarray:
    """The blend weight in [0, 1] of each particle of ring `levels` at (x, z), seen from `eye`.

    Inside the band where level k - 1 fades out, level k fades in with the
    complementary weight; beyond its reach it is 0.
    """
    levels = np.asarray(levels, dtype=np.int64)
    distance = chebyshev_distances(x, z, eye)
    side = field.cell_size * np.exp2(levels.astype(np.float64))
    reach = RING_HALF_CELLS * side
    fade_out = 1.0 - smoothstep(reach - side, reach, distance)
    # the band of the ring inside: its reach less one of its cells, to its reach
    inner_side, inner_reach = 0.5 * side, 0.5 * reach
    fade_in = np.where(levels > 0, smoothstep(inner_reach - inner_side, inner_reach, distance), 1.0)
    return fade_in * fade_out


def cells_in_reach(field: CloudField, level: int, eye) -> list[tuple[int, int]]:
    """The cells (i, j) of `level` inside the field with some point where the level's weight is above zero.

    Cell (i, j) spans x in centre_x + [i, i + 1] side, z likewise.  At most
    (2 RING_HALF_CELLS + 2)^2 cells, whatever the field's extent.
    """
    side = cell_side(field, level)
    lo, hi = level_support(field, level)
    eye = np.asarray(eye, dtype=np.float64)
    ranges = []
    for axis, (centre, extent) in enumerate(zip(field.centre, field.extent)):
        position = eye[2 * axis] - centre
        first_in_field, last_in_field = math.floor(-0.5 * extent / side), math.ceil(0.5 * extent / side) - 1
        # clipped to the field before the conversion to int: an eye far away gives no cells, not an overflow
        first = max(first_in_field, math.floor(max((position - hi) / side, first_in_field - 1)))
        last = min(last_in_field, math.floor(min((position + hi) / side, last_in_field + 1)))
        ranges.append((first, last, position))
    (i0, i1, px), (j0, j1, pz) = ranges
    if i0 > i1 or j0 > j1:
        return []
    i, j = np.meshgrid(np.arange(i0, i1 + 1), np.arange(j0, j1 + 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    near_x, far_x = _axis_range(i * side - px, (i + 1) * side - px)
    near_z, far_z = _axis_range(j * side - pz, (j + 1) * side - pz)
    nearest, farthest = np.maximum(near_x, near_z), np.maximum(far_x, far_z)
    keep = (nearest < hi) & (farthest > lo)
    return [(int(a), int(b)) for a, b in zip(i[keep], j[keep])]


def _axis_range(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest and farthest |offset| over the intervals [low, high] (offsets from the eye along one axis)."""
    nearest = np.maximum(0.0, np.maximum(low, -high))
    return nearest, np.maximum(np.abs(low), np.abs(high))
