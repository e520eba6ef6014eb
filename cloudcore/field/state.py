"""What of a cloud field is made now, and the pure step that follows the eye: only entering cells are made.

`update_field(field, eye, state) -> (FieldFrame, FieldState)`: the cells in
reach of each ring (`cloudcore.field.grid.cells_in_reach`) that the state
does not hold are generated (`cloudcore.field.cells.cell_cloud`), those out
of reach are dropped, and the rest are the very same `Cloud` objects as
before, so the illumination cache (by cloud identity) lights only the new
ones.  The field's clouds keep their places in the frame's cloud list: an
entering cell takes a place a leaving one freed (a hole, an empty cloud,
until then), so the clouds that stay keep their indices, and with them their
impostors and representations in the frame plan.  The frame carries every
particle's blend weight for the eye (`cloudcore.field.grid.level_weights`)
and, per cloud, a key that changes when its weights do (its impostor is then
stale).  The cost of a step follows the rings, not the field's extent.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from cloudcore.field.cells import cell_clouds
from cloudcore.field.grid import cells_in_reach, level_weights
from cloudcore.model.scene import Cloud, CloudField

#: a cell: (level, i, j)
CellKey = tuple[int, int, int]
#: the place of a cell that left, until an entering one takes it: no particles, nothing drawn
HOLE = Cloud("field_hole")
#: a cloud's blend weight is told to the frame plan in steps of 1 / FADE_KEY_STEPS: its impostor is remade at each
#: step while it blends and drawn meanwhile with its opacity scaled by its mean weight now over its mean weight when
#: made (`FrameRenderer`), which holds the picture as close to full 3D as 1/16 steps without the scaling did with a
#: quarter of the remakes (docs/performance.md, "Impostors that follow a field's fade")
FADE_KEY_STEPS = 4


@dataclass(frozen=True)
class FieldState:
    """The cells made for the last eye (pure; the renderer holds one between frames)."""

    field: CloudField | None = None  # what the cells were made from
    cells: Mapping = dataclasses.field(default_factory=dict)  # CellKey -> its Cloud, or None for clear sky
    slots: tuple = ()  # the field's clouds in frame order: a CellKey, or None for a hole
    made: tuple = ()  # the cells the step that returned this state made
    dropped: int = 0  # ... and how many it dropped
    # the slots' particles, concatenated: (x, z) and ring level, for the per-frame weights
    particle_xz: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))
    particle_levels: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    cloud_starts: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(1, dtype=np.int64))


@dataclass(frozen=True)
class FieldFrame:
    """The field's clouds for one eye: the clouds in their places, each particle's weight, each cloud's mean weight
    and key."""

    clouds: tuple  # of Cloud (HOLE where a place is free)
    weights: np.ndarray  # (particles of `clouds`,) blend weights in [0, 1]
    mean_weights: np.ndarray  # (len(clouds),) each cloud's particles' mean weight (1 for a hole)
    fade_keys: tuple  # per cloud: changes whenever its weights change by more than scaling its impostor hides
    cloud_starts: np.ndarray  # (len(clouds) + 1,) where each cloud's particles start in `weights`

    @classmethod
    def weighed(cls, clouds: tuple, weights: np.ndarray, cloud_starts: np.ndarray) -> FieldFrame:
        """The frame of `clouds` whose particles weigh `weights`, its clouds' means and keys made from them."""
        return cls(clouds, weights, *_cloud_weights(weights, cloud_starts), cloud_starts)

    @property
    def particle_count(self) -> int:
        return len(self.weights)


def side_by_side(frames, weights, places, leading: int) -> FieldFrame:
    """Frames of several fields as one, their particles weighing `weights` (one array a frame: its own, or scaled):
    `leading` holes first, then each frame's clouds in `places` of its own (its count of clouds, or more: holes
    after them), so a field's clouds keep their indices while another's change.  One frame alone in its places,
    weighing its own weights, is itself."""
    if len(frames) == 1 and leading == 0 and places[0] == len(frames[0].clouds) and weights[0] is frames[0].weights:
        return frames[0]
    clouds, starts, end = [HOLE] * leading, [np.zeros(leading + 1, dtype=np.int64)], 0
    for frame, room in zip(frames, places):
        clouds += [*frame.clouds, *[HOLE] * (room - len(frame.clouds))]
        starts.append(end + frame.cloud_starts[1:])
        end += frame.particle_count
        starts.append(np.full(room - len(frame.clouds), end, dtype=np.int64))
    return FieldFrame.weighed(tuple(clouds), np.concatenate(weights), np.concatenate(starts))


def update_field(field: CloudField, eye, state: FieldState = FieldState()) -> tuple[FieldFrame, FieldState]:
    """The field's clouds for `eye` and the state to carry on; a field that changed is made anew."""
    eye = np.asarray(eye, dtype=np.float64)
    if state.field != field:
        state = FieldState(field)
    wanted = {(level, i, j) for level in range(field.rings) for i, j in cells_in_reach(field, level, eye)}
    made = tuple(sorted(key for key in wanted if key not in state.cells))
    cells = {key: cloud for key, cloud in state.cells.items() if key in wanted}
    cells.update(zip(made, cell_clouds(field, made)))
    dropped = len(state.cells) - (len(cells) - len(made))
    if made or dropped:
        state = _placed(field, cells, state.slots, made, dropped)
    elif state.made or state.dropped:
        state = dataclasses.replace(state, made=(), dropped=0)
    clouds = tuple(HOLE if key is None else state.cells[key] for key in state.slots)
    weights = level_weights(field, state.particle_levels, state.particle_xz[:, 0], state.particle_xz[:, 1], eye)
    return FieldFrame.weighed(clouds, weights, state.cloud_starts), state


def _placed(field: CloudField, cells: dict, slots: tuple, made: tuple, dropped: int) -> FieldState:
    """The state holding `cells`: cells that stay keep their slot, entering clouds fill freed slots first."""
    slots = [key if key in cells else None for key in slots]
    free = iter([index for index, key in enumerate(slots) if key is None])
    for key in made:
        if cells[key] is None:
            continue
        index = next(free, None)
        if index is None:
            slots.append(key)
        else:
            slots[index] = key
    while slots and slots[-1] is None:
        slots.pop()
    clouds = [HOLE if key is None else cells[key] for key in slots]
    counts = np.array([len(c.particles) for c in clouds], dtype=np.int64)
    particles = np.concatenate([c.particles for c in clouds]) if clouds else np.zeros((0, 4))
    levels = np.repeat([0 if key is None else key[0] for key in slots], counts).astype(np.int64)
    return FieldState(
        field,
        cells,
        tuple(slots),
        made,
        dropped,
        particles[:, [0, 2]],
        levels,
        np.concatenate([[0], np.cumsum(counts)]),
    )


def _cloud_weights(weights: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, tuple]:
    """(per cloud its particles' mean weight, its fade key): the mean rounded up to a step of 1 / FADE_KEY_STEPS,
    so that only a cloud at weight 0 has key 0 (its impostor, empty, is never scaled up); a cloud wholly at
    weight 1, or empty: exactly 1."""
    counts = np.diff(starts)
    means, keys = np.ones(len(counts)), np.ones(len(counts))
    filled = counts > 0
    if filled.any():
        firsts = starts[:-1][filled]
        means[filled] = np.add.reduceat(weights, firsts) / counts[filled]
        blending = np.flatnonzero(filled)[np.minimum.reduceat(weights, firsts) < 1.0]
        keys[blending] = np.ceil(means[blending] * FADE_KEY_STEPS) / FADE_KEY_STEPS
    return means, tuple(float(key) for key in keys)
