"""A cloud field's clouds as the light pass's shadows between clouds see them: each cloud's cell, and how much of
its opacity each particle casts on the other cells.

The nested grid's rings overlap (`cloudcore.field.grid`): in a blend band a cumulus is made twice, by a cell of
level k and by the cell of level k + 1 over it, their weights summing to one.  Each representation lit through
the other would take the same cloud's body twice (Harris's light pass already shades a cell's particles through
their own cell), so a cell's particles take no shadow from particles whose place lies in its own footprint, of any
level (its own particles, and the finer cells that stand for the same cloud).  Every other particle casts its
opacity times its blend weight, the weight it is drawn with: the field is read as one medium whose representations'
weights sum to one at each place, and a cell that enters or leaves at weight 0 casts nothing then, so that nothing
steps as it comes or goes.  The weights are those of the frame whose cells changed, each cloud's mean in steps of
1 / FADE_KEY_STEPS: the light pass is made again when cells enter or leave, as before, and then for the weights of
that moment; made again at every step of a cloud's weight, it was made in every frame of a flight
(docs/atmosphere.md#a-cloud-fields-clouds-on-one-another).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.field.grid import cell_side
from cloudcore.field.state import FADE_KEY_STEPS, FieldState


@dataclass(frozen=True, eq=False)
class CellShadowing:
    """Per cloud of a frame (the scene's own, then the field's in their places) its cell's footprint, and per
    particle how much of its opacity it casts on other clouds.  Compared by identity: a frame renderer makes one per
    set of cells and of their casting steps."""

    corners: np.ndarray  # (clouds, 2) the (x, z) corner of each cloud's cell: NaN for the scene's own clouds
    sides: np.ndarray  # (clouds,) metres: each cell's side (NaN likewise)
    casting: np.ndarray  # (particles,) in [0, 1]: the share of its opacity it casts (`casting_weights`)


def casting_weights(mean_weights, cloud_starts) -> np.ndarray:
    """(particles,): the share of its opacity each particle casts on other cells, its cloud's mean blend weight
    (`mean_weights`, its particles at `cloud_starts`) in steps of 1 / FADE_KEY_STEPS, rounded (a cloud under half a
    step casts none).  A cloud's step, not each particle's weight: where cells change, only the clouds whose step
    changed since are met again as casters, where every blending cloud's particles had changed."""
    steps = np.round(np.clip(np.asarray(mean_weights, dtype=np.float64), 0.0, 1.0) * FADE_KEY_STEPS) / FADE_KEY_STEPS
    return np.repeat(steps, np.diff(np.asarray(cloud_starts, dtype=np.int64)))


def cell_shadowing(authored_clouds: int, parts, places, leading: int, casting) -> CellShadowing:
    """The shadowing of a frame made of `authored_clouds` clouds and then, after `leading` holes, each `FieldState`
    of `parts` in `places` of its own (as `cloudcore.field.state.side_by_side` lays them out), its particles (the
    authored clouds' first) casting `casting` of their opacities (`casting_weights`)."""
    corners = [np.full((authored_clouds + leading, 2), np.nan)]
    sides = [np.full(authored_clouds + leading, np.nan)]
    for part, room in zip(parts, places):
        part_corners, part_sides = _cell_footprints(part)
        corners += [part_corners, np.full((room - len(part.slots), 2), np.nan)]
        sides += [part_sides, np.full(room - len(part.slots), np.nan)]
    return CellShadowing(np.concatenate(corners), np.concatenate(sides), np.asarray(casting, dtype=np.float64))


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
