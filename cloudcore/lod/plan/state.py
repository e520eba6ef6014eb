"""What the level of detail carries from one frame to the next: the impostors held, the ring, each unit's
representation, the fitted costs, and auto mode's measured frame times (pure; the renderer holds one)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from cloudcore.lod.costs import CostEstimator, CostModel
from cloudcore.lod.ring import (
    RingCandidates,
    RingState,
)

#: auto mode's choice between a frame of units each as priced and one all in full 3D is by the frames' measured
#: times (the cost model, fitted to what is drawn, predicts the other poorly): the frames after a switch that do
#: not count (crossfades and the ring's fade), the measured frames a choice needs, the age in frames after which
#: the other's measurement is stale, and how close its predicted time must come for the other to be tried at all
#: (a scene where full 3D is predicted four times dearer never stalls to find out)
FRAME_SETTLE_FRAMES = 16
PROBE_FRAMES = 8
MEASUREMENT_AGE_FRAMES = 300
PLAUSIBLE_RATIO = 1.5


#: auto mode prices Wang's ring against its clouds drawn alone (`choice.ring_prices_hold`) again after this many
#: frames (the cost fit moves), or sooner once the eye has turned this far or moved this share of a rebuild distance,
#: or the count of its clouds in view or a coefficient of the cost model has changed by this share (the choice's
#: margin, `choice.SWITCH_MARGIN`, is 25%)
RING_PRICE_FRAMES = 16
RING_PRICE_TURN_DEG = 2.0
RING_PRICE_MOVE_SHARE = 0.25
RING_PRICE_CHANGE_SHARE = 0.1


#: the running mean of a choice's frame times weighs each new frame at least this much
FRAME_TIME_FORGETTING = 0.1


@dataclass(frozen=True)
class Representation:
    """Auto mode's choice for a unit: where it is heading and how far it has come (1 = all full 3D)."""

    target: str  # "full" or "impostor"
    full_weight: float


@dataclass(frozen=True)
class RingPrices:
    """Auto mode's pricing of Wang's ring against its clouds drawn each on their own, and the view it was made for."""

    eye: tuple
    back: tuple  # the view matrix's third row: the eye looks along its negative
    frame_index: int  # `LodState.frame_index` when priced
    generation: object  # the ring's newest generation then (`RingState.pending` or `current`)
    costs: CostModel  # the model that priced it
    units: object  # the `LodUnits` priced
    in_view: int  # the ring's clouds in view then
    #: per unit, its (particles, fragments) drawn in full 3D far off, the ring's candidates in view counted splat
    #: by splat (`pricing.in_view_work`), for the prediction of the frame all in full 3D
    in_view_work: tuple
    ring_ms: float  # its panels a frame and its rebuild amortised over its lifetime
    alone_ms: float  # its clouds in view drawn each as auto would (`pricing.ms_drawn_alone`)


@dataclass(frozen=True)
class LodState:
    """What the level of detail carries from one frame to the next (pure; the renderer holds one)."""

    records: Mapping = field(default_factory=dict)  # unit members -> ImpostorRecord: the impostor cache
    ring: RingState = RingState()
    representations: Mapping = field(default_factory=dict)  # unit members -> Representation (auto mode)
    eye: tuple | None = None  # last frame's eye: the speed that predicts an impostor's lifetime
    costs: CostEstimator = CostEstimator()
    #: auto mode draws a frame's units each as its price says ("units"), or every one in full 3D ("full"):
    #: the choice for the next frame, the one this frame was drawn with and for how many frames in a row
    frame_choice: str | None = None
    drawn_as: str | None = None
    frames_drawn_as: int = 0
    frame_index: int = 0  # frames planned
    frame_times: Mapping = field(default_factory=dict)  # choice -> FrameTime: how long its frames took, measured
    #: the units' particles when last planned: a scene changed past `SCENE_CHANGE_RATIO` forgets `frame_times`
    particles: float = 0.0
    opened: frozenset = frozenset()  # the groups of clouds planned apart (`groups_cheaper_apart`)
    ring_prices: RingPrices | None = None  # auto mode's last pricing of the ring (`choice.ring_prices_hold`)
    ring_candidates: RingCandidates | None = None  # auto mode's units in the ring, held by their slack
    object_centres: tuple = ()  # the objects' bounding-sphere centres: which of them move
    #: the units near the eye priced splat by splat last frame, for the same view to ask again (a still eye):
    #: (units, camera, viewport, {members: (their clouds' keys, Work)}), or None
    near_work: tuple | None = None
    #: last frame's scene clock under wind (None: still air): the wind's step since carries the units
    time_s: float | None = None
    #: the scale of last frame's cloud pass (`FramePlan.cloud_scale`; None: no frame planned yet), which a choice by
    #: price keeps within a margin
    cloud_scale: float | None = None

    def measured(self, measurements, fit: bool = True, plan_ms: float = 0.0) -> LodState:
        """The state with this frame's (predicted work, measured ms) pairs folded into the cost fit (unless not
        `fit`: a frame planned without prices), and their sum with the plan's own `plan_ms` into the measured time
        of the way the frame was drawn (once the switch to it has settled): a frame of units priced one by one
        plans for longer than one all in full 3D planned as full mode plans it (the cumulus field under wind: 4-9
        against 1.5 ms), which the passes' times alone do not show."""
        frame_times = self.frame_times
        total_ms = sum(ms for _, ms in measurements if math.isfinite(ms) and ms >= 0.0)
        total_ms += plan_ms if math.isfinite(plan_ms) and plan_ms > 0.0 else 0.0
        if self.drawn_as is not None and self.frames_drawn_as > FRAME_SETTLE_FRAMES:
            held = frame_times.get(self.drawn_as)
            running = held is not None and held.last_frame == self.frame_index - 1
            frame_times = {
                **frame_times,
                self.drawn_as: FrameTime.after(held if running else None, total_ms, self.frame_index),
            }
        costs = self.costs.observe(measurements) if fit else self.costs
        return dataclasses.replace(self, costs=costs, frame_times=frame_times)


@dataclass(frozen=True)
class FrameTime:
    """The measured time of the frames drawn one way, in a running mean over its last run of frames."""

    mean_ms: float
    frames: int
    last_frame: int  # `LodState.frame_index` of the last frame measured

    @staticmethod
    def after(previous: FrameTime | None, ms: float, frame: int) -> FrameTime:
        if previous is None:
            return FrameTime(ms, 1, frame)
        weight = max(1.0 / (previous.frames + 1), FRAME_TIME_FORGETTING)
        return FrameTime((1.0 - weight) * previous.mean_ms + weight * ms, previous.frames + 1, frame)
