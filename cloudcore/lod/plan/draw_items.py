"""The cloud pass far to near, as arrays: the drawn units' layers and the objects between them.

`draw_items` orders what the frame plan draws on its own (`cloudcore.lod.plan`): a unit drawn whole
is one item at its distance, a unit that objects split is one item per layer, and each object inside a
drawn unit is one item between its layers.  Full 3D draws every unit in view (thousands at Harris's scale),
so the items are rows of arrays, ordered in one sort; `DrawItems[i]` gives the i-th as a `DrawItem`.
`inside_runs` and `full_runs` read the runs the GL side draws together.  Pure numpy.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from cloudcore.lod.plan.unit_plans import CROSSFADE, FULL, INSIDE, UnitPlans
from cloudcore.lod.splitting import layer_bounds, layer_sort_key
from cloudcore.lod.units import concatenated_ranges

ITEM_KINDS = ("cloud", "object")
CLOUD, OBJECT = range(len(ITEM_KINDS))


@dataclass(frozen=True)
class DrawItem:
    """One step of the cloud pass: a layer of a unit, or an object drawn between layers."""

    kind: str  # "cloud" or "object"
    index: int
    depth: float  # distance from the eye the pass is sorted by, far to near
    layer: int = 0  # of the unit, 0 the farthest
    near: float = -math.inf  # the layer holds the particles with near < distance from the eye <= far
    far: float = math.inf


@dataclass(frozen=True, eq=False)
class DrawItems(Sequence):
    """The cloud pass far to near, one row per item."""

    kinds: np.ndarray  # (items,) CLOUD or OBJECT
    indices: np.ndarray  # (items,) the unit's, or the object's
    depths: np.ndarray
    layers: np.ndarray
    nears: np.ndarray
    fars: np.ndarray

    def __len__(self) -> int:
        return len(self.kinds)

    def __getitem__(self, position: int) -> DrawItem:
        position = range(len(self))[position]
        return DrawItem(
            ITEM_KINDS[self.kinds[position]],
            int(self.indices[position]),
            float(self.depths[position]),
            int(self.layers[position]),
            float(self.nears[position]),
            float(self.fars[position]),
        )

    def __iter__(self) -> Iterator[DrawItem]:
        return (self[position] for position in range(len(self)))

    @property
    def objects(self) -> tuple:
        """The objects drawn between layers, far to near."""
        return tuple(self.indices[self.kinds == OBJECT].tolist())


def draw_items(plans: UnitPlans, draw_order, radii, object_centres, objects_visible, eye) -> DrawItems:
    """The cloud pass far to near of the units `draw_order` (far to near): each unit's layers, and each object
    that splits one once between them (the visible ones)."""
    order = np.asarray(draw_order, dtype=np.int64)
    counts = np.ones(len(order), dtype=np.int64)
    split = [(position, index) for position, index in enumerate(draw_order) if plans.splits.get(index)]
    for position, index in split:
        counts[position] = len(plans.splits[index]) + 1
    starts = np.cumsum(counts) - counts
    indices = np.repeat(order, counts)
    layers = concatenated_ranges(np.zeros(len(order)), counts)
    depths = np.repeat(plans.distances[order], counts)
    nears, fars = np.full(len(indices), -math.inf), np.full(len(indices), math.inf)
    for position, index in split:  # a layer stands at the middle of its depth range within the unit
        splits, distance = plans.splits[index], float(plans.distances[index])
        for layer in range(len(splits) + 1):
            row = starts[position] + layer
            nears[row], fars[row] = layer_bounds(splits, layer)
            depths[row] = layer_sort_key(nears[row], fars[row], distance, radii[index])
    kinds = np.full(len(indices), CLOUD, dtype=np.int8)
    inside = sorted({o for _, index in split for o in plans.split_objects.get(index, ())})
    shown = np.array([o for o in inside if objects_visible[o]], dtype=np.int64)
    if len(shown):
        distances = np.array([np.linalg.norm(object_centres[o] - eye) for o in shown], dtype=np.float64)
        kinds = np.concatenate([kinds, np.full(len(shown), OBJECT, dtype=np.int8)])
        indices = np.concatenate([indices, shown])
        depths, nears, fars = (np.concatenate([column, distances]) for column in (depths, nears, fars))
        layers = np.concatenate([layers, np.zeros(len(shown), dtype=np.int64)])
    # far to near; at equal depth the layer reaching farther first, then objects before layers (a stable sort)
    ranked = np.lexsort((kinds != OBJECT, -fars, -depths))
    return DrawItems(kinds[ranked], indices[ranked], depths[ranked], layers[ranked], nears[ranked], fars[ranked])


def inside_runs(items: DrawItems, plans: UnitPlans) -> list[list]:
    """The draw items of units the eye is inside, in runs that share one screen impostor: consecutive in
    the cloud pass and drawn at the same weight (nothing is drawn between them, so one sorted batch and
    one composite give the picture of each drawn in turn, with their particles sorted together)."""
    clouds = items.kinds == CLOUD
    inside = np.zeros(len(items), dtype=bool)
    inside[clouds] = plans.kinds[items.indices[clouds]] == INSIDE
    inside = np.flatnonzero(inside).tolist()
    runs, previous = [], None  # previous: (position, full weight) of the item before in a run
    for position in inside:
        weight = plans.full_weights[items.indices[position]]
        if previous is not None and previous == (position - 1, weight):
            runs[-1].append(items[position])
        else:
            runs.append([items[position]])
        previous = (position, weight)
    return runs


def full_runs(kinds: np.ndarray) -> int:
    """Splat draws of the cloud pass outside screen impostors, the units' `kinds` in draw order: each run of
    consecutive full units is one, each crossfading unit one."""
    full = kinds == FULL
    starts = full & ~np.concatenate([[False], full[:-1]])
    return int(np.count_nonzero(starts) + np.count_nonzero(kinds == CROSSFADE))
