"""What a frame's plan chose, counted: the statistics `FramePlan.stats` gives (pure); a frame's are
`cloudcore.stats.frame_stats.FrameStats`, this and what the renderer measured."""

from __future__ import annotations

from dataclasses import dataclass, field

from cloudcore.lod.costs import CostModel


@dataclass(frozen=True)
class PlanStats:
    """What the frame plan chose (`FramePlan.stats`); the defaults are an empty plan's."""

    #: clouds (not units) per draw kind; `FramePlan.stats` names every kind of `cloudcore.lod.plan.KINDS`
    clouds_by_kind: dict[str, int] = field(default_factory=dict)
    units: int = 0
    units_grouped: int = 0  # units of several interpenetrating clouds
    impostors_drawn: int = 0
    impostors_regenerated: int = 0
    regeneration_reasons: dict[str, int] = field(default_factory=dict)
    regenerations_postponed: int = 0
    ring_segments_built: int = 0
    ring_panels_drawn: int = 0
    objects_in_clouds: int = 0
    layers_drawn: int = 0
    layers_rebuilt: int = 0
    predicted_ms: float = 0.0
    priced: bool = True  # False in full 3D, which prices nothing: predicted_ms is then 0
    tolerance_deg: float = 0.0
    accepted_error_tolerances: float = 0.0  # the largest error drawn, in tolerances
    #: auto mode: the frame drawn with its units each as priced ("units") or all in full 3D ("full"; "" in the
    #: other modes), and the measured times of frames drawn each way (`cloudcore.lod.plan.FrameTime`; 0: not yet)
    drawn_as: str = ""
    measured_units_ms: float = 0.0
    measured_full_ms: float = 0.0
    costs: CostModel = field(default_factory=CostModel)  # the coefficients the plan priced its choices with
    cloud_scale: float = 1.0  # per axis, the cloud pass's fraction of the screen's resolution (`FramePlan.cloud_scale`)
