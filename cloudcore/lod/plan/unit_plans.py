"""What the frame plan decided for each unit, as arrays: a unit costs Python time only where it is drawn.

A plan holds one decision per unit of the scene, seen or not (`cloudcore.lod.plan`); most of a large
scene's units are out of view or in Wang's ring, and Harris's 12,800 clouds made 12,800 records a frame.
`UnitPlans` keeps the decisions as arrays, one row per unit, and the few things only a regenerated or split
unit has (why it is remade, the objects that split it) in small mappings by unit index.  Indexing it gives a
`CloudPlan`, made on the spot: the GL side and the tests read the units they draw that way, and whole-scene
questions (how many clouds of each kind, whether anything is left to converge) are answered over the arrays.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

KINDS = ("empty", "culled", "ring", "full", "crossfade", "impostor", "inside")
EMPTY, CULLED, RING, FULL, CROSSFADE, IMPOSTOR, INSIDE = range(len(KINDS))
#: kinds that draw from an impostor texture kept in the cache
TEXTURED = ("crossfade", "impostor")
#: kinds drawn in the cloud pass, each unit on its own
DRAWN = ("full", "crossfade", "impostor", "inside")


def kind_codes(*kinds: str) -> np.ndarray:
    """The codes of `kinds` in `UnitPlans.kinds`."""
    return np.array([KINDS.index(kind) for kind in kinds], dtype=np.int8)


def of_kinds(codes: np.ndarray, *kinds: str) -> np.ndarray:
    """Boolean, per code of `codes` (`UnitPlans.kinds`): whether it is one of `kinds` (a table looked up by code:
    `np.isin` sorts, and the plan asks several times a frame)."""
    table = np.zeros(len(KINDS), dtype=bool)
    table[kind_codes(*kinds)] = True
    return table[codes]


class CloudPlan(NamedTuple):
    """One unit's plan (`UnitPlans[index]`)."""

    index: int  # the unit's
    kind: str
    distance: float
    full_weight: float = 0.0  # share of opacity drawn from particles (full, crossfade, inside)
    impostor_weight: float = 0.0  # share drawn from the cached impostor
    regenerate: str | None = None  # why the impostor is remade this frame
    postponed: str | None = None  # why it would be, had the regeneration budget allowed it
    texture_size: int = 0  # side of the impostor texture used
    split_objects: tuple = ()  # indices of the objects inside it, far to near
    splits: tuple = ()  # their distances from the eye: the layers' boundaries
    members: tuple = ()  # the clouds of the unit
    full_ms: float = 0.0  # predicted cost of full 3D this frame (0 in impostor mode, which never draws it)
    impostor_ms: float = 0.0  # auto mode: predicted cost of the impostor per frame, its regeneration amortised

    @property
    def layers(self) -> int:
        return len(self.splits) + 1


@dataclass(frozen=True, eq=False)
class UnitPlans(Sequence):
    """Per unit (rows in the units' order) what the plan decided; `self[i]` is unit i's `CloudPlan`."""

    kinds: np.ndarray  # (units,) int8: codes into KINDS
    distances: np.ndarray  # (units,) of the unit's centre from the eye
    members: tuple  # per unit, its clouds
    member_counts: np.ndarray  # (units,) clouds per unit
    full_weights: np.ndarray = None
    impostor_weights: np.ndarray = None
    texture_sizes: np.ndarray = None
    full_ms: np.ndarray = None
    impostor_ms: np.ndarray = None
    regenerate: Mapping = field(default_factory=dict)  # unit -> why its impostor is remade this frame
    postponed: Mapping = field(default_factory=dict)  # unit -> why it would have been
    split_objects: Mapping = field(default_factory=dict)  # unit -> the objects inside it, far to near
    splits: Mapping = field(default_factory=dict)  # unit -> their distances from the eye

    def __post_init__(self):
        zeros = np.zeros(len(self.kinds))
        for name in ("full_weights", "impostor_weights", "full_ms", "impostor_ms"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, zeros)
        if self.texture_sizes is None:
            object.__setattr__(self, "texture_sizes", np.zeros(len(self.kinds), dtype=np.int64))

    def __len__(self) -> int:
        return len(self.kinds)

    def __getitem__(self, index: int) -> CloudPlan:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        index = range(len(self))[index]
        return CloudPlan(
            index,
            KINDS[self.kinds[index]],
            float(self.distances[index]),
            float(self.full_weights[index]),
            float(self.impostor_weights[index]),
            self.regenerate.get(index),
            self.postponed.get(index),
            int(self.texture_sizes[index]),
            self.split_objects.get(index, ()),
            self.splits.get(index, ()),
            self.members[index],
            float(self.full_ms[index]),
            float(self.impostor_ms[index]),
        )

    def __iter__(self) -> Iterator[CloudPlan]:
        return (self[index] for index in range(len(self)))

    def indices_of(self, *kinds: str) -> np.ndarray:
        """The units of `kinds`, ascending."""
        return np.flatnonzero(of_kinds(self.kinds, *kinds))

    def count(self, *kinds: str) -> int:
        """How many units are of `kinds`."""
        return int(np.count_nonzero(of_kinds(self.kinds, *kinds)))

    def inside_as_full(self) -> UnitPlans:
        """The plans with the units the eye is in drawn in full 3D (whole: not fading into the ring), as a reduced cloud
        pass no finer than their screen impostor draws them."""
        kinds = np.where((self.kinds == INSIDE) & (self.full_weights == 1.0), FULL, self.kinds).astype(np.int8)
        return replace(self, kinds=kinds)

    def clouds_by_kind(self) -> dict:
        """Clouds (not units) per kind, every kind of KINDS named."""
        counts = np.bincount(self.kinds, weights=self.member_counts, minlength=len(KINDS))
        return {kind: int(count) for kind, count in zip(KINDS, counts)}
