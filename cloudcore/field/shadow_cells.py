"""A cloud field's clouds as the light pass's shadows between clouds see them: each cloud's cell, and which
particles stand for the field in another cloud's shadow.

The nested grid's rings overlap (`cloudcore.field.grid`): in a blend band a cumulus is made twice, by a cell of
level k and by the cell of level k + 1 over it, their weights summing to one.  Each representation lit through
the other would take the same cloud's body twice (Harris's light pass already shades a cell's particles through
their own cell), so the clouds' shadows on one another read the field as one medium, the finest made at each
place: a particle shadows other cells unless a made cell of a finer level (cloudy or clear) covers its place, and a
cell's particles take no shadow from particles whose place lies in its own footprint, of any level (its own
particles, and the finer cells that stand for the same cloud).  Both follow the cells made, not the eye's place
within them: the shadows change when cells enter or leave, never as the blend weights slide
(docs/atmosphere.md#a-cloud-fields-clouds-on-one-another).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.field.grid import cell_side
from cloudcore.field.state import FieldState


@dataclass(frozen=True, eq=False)
class CellShadowing:
    """Per cloud of a frame (the scene's own, then the field's in their places) its cell's footprint, and per
    particle whether it shadows other clouds.  Compared by identity: a frame renderer makes one per set of cells."""

    corners: np.ndarray  # (clouds, 2) the (x, z) corner of each cloud's cell: NaN for the scene's own clouds
    sides: np.ndarray  # (clouds,) metres: each cell's side (NaN likewise)
    occludes: np.ndarray  # (particles,) bool: the finest made representation of the field at its place


def cell_shadowing(authored_clouds: int, authored_particles: int, parts, places, leading: int) -> CellShadowing:
    """The shadowing of a frame made of `authored_clouds` clouds (`authored_particles` particles) and then, after
    `leading` holes, each `FieldState` of `parts` in `places` of its own (as `cloudcore.field.state.side_by_side`
    lays them out)."""
    corners = [np.full((authored_clouds + leading, 2), np.nan)]
    sides = [np.full(authored_clouds + leading, np.nan)]
    occludes = [np.ones(authored_particles, dtype=bool)]
    for part, room in zip(parts, places):
        part_corners, part_sides = _cell_footprints(part)
        corners += [part_corners, np.full((room - len(part.slots), 2), np.nan)]
        sides += [part_sides, np.full(room - len(part.slots), np.nan)]
        occludes.append(_finest_made(part))
    return CellShadowing(np.concatenate(corners), np.concatenate(sides), np.concatenate(occludes))


def _cell_footprints(state: FieldState) -> tuple[np.ndarray, np.ndarray]:
    """((slots, 2) corners, (slots,) sides) of the state's clouds' cells (NaN for a hole)."""
    corners, sides = np.full((len(state.slots), 2), np.nan), np.full(len(state.slots), np.nan)
    if state.field is None:
        return corners, sides
    for index, key in enumerate(state.slots):  # the slots, not the field's particles: a few hundred at most
        if key is not None:
            level, i, j = key
            sides[index] = cell_side(state.field, level)
            corners[index] = np.asarray(state.field.centre) + sides[index] * np.array([i, j])
    return corners, sides


def _finest_made(state: FieldState) -> np.ndarray:
    """(particles of the state's slots,) whether no made cell of a finer level covers each particle's place."""
    levels, xz = state.particle_levels, state.particle_xz
    finest = np.ones(len(levels), dtype=bool)
    if state.field is None or not len(levels):
        return finest
    made = np.array(list(state.cells), dtype=np.int64).reshape(-1, 3)
    centre = np.asarray(state.field.centre)
    for finer in range(int(levels.max())):
        of_level = made[made[:, 0] == finer, 1:]
        coarser = np.flatnonzero(levels > finer)
        if not len(of_level) or not len(coarser):
            continue
        cell = np.floor((xz[coarser] - centre) / cell_side(state.field, finer)).astype(np.int64)
        finest[coarser[_rows_in(cell, of_level)]] = False
    return finest


def _rows_in(rows: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Whether each (i, j) row of `rows` is one of `table`'s."""
    low = np.minimum(rows.min(axis=0), table.min(axis=0))
    span = np.maximum(rows.max(axis=0), table.max(axis=0)) - low + 1
    return np.isin((rows - low) @ [span[1], 1], (table - low) @ [span[1], 1])
