"""A frame's plan: per unit what was decided, the cloud pass in order, the ring, the work predicted, and the
state to carry into the next frame; its statistics (`plan_stats`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from cloudcore.lod.costs import CostModel, Work
from cloudcore.lod.plan.draw_items import DrawItems
from cloudcore.lod.plan.plan_stats import PlanStats
from cloudcore.lod.plan.state import LodState
from cloudcore.lod.plan.unit_plans import (
    TEXTURED,
    UnitPlans,
)
from cloudcore.lod.ring import (
    RingPlan,
    RingState,
)
from cloudcore.lod.units import LodUnits


@dataclass(frozen=True)
class FramePlan:
    clouds: UnitPlans  # per unit, what was decided: `clouds[i]` is unit i's CloudPlan
    draw_order: tuple  # indices of the units drawn individually, far to near
    ring: RingPlan | None
    state: LodState = LodState()  # to carry into the next frame
    inside_size: tuple = (0, 0)  # the screen impostor's texture size (width, height)
    #: the cloud pass's size (width, height): the screen's, or less (`settings.cloud_resolution_scale`), upsampled
    cloud_size: tuple = (0, 0)
    cloud_scale: float = 1.0  # per axis, the cloud pass's fraction of the screen's resolution
    draw_items: DrawItems | None = None  # the cloud pass, far to near
    objects_with_world: tuple = ()  # visible objects outside split clouds: drawn before the cloud pass
    update_work: Work = Work()  # predicted work of the impostor updates (regenerations, ring segment)
    cloud_work: Work = Work()  # predicted work of the cloud pass
    #: whether the works above were priced: full 3D draws every unit in view whatever it costs, so it prices
    #: nothing (its works are empty and its frames fit no costs: `LodState.measured`)
    priced: bool = True
    costs: CostModel = CostModel()  # the model the plan priced its choices with
    tolerance_deg: float = 0.0  # the translation tolerance in force
    #: the largest translation error drawn, in tolerances (> 1: a budget postponed it, or Wang's ring shown while
    #: its rebuild, begun once its error passed the tolerance, is under way)
    accepted_error: float = 0.0
    units: LodUnits | None = None  # the frame's units, which `clouds` index: the groups planned apart opened
    #: (units, 3) metres the wind has carried each unit (`cloudcore.world.wind`); None: still air
    unit_drifts: np.ndarray | None = None
    #: per generation of `ring.draws`, (3,) metres the wind has carried its clouds since it was planned: its panels
    #: follow them
    ring_shifts: tuple = ()
    #: the same for the generation whose segments this frame builds: they are rendered as its clouds were when it was
    #: planned, so that all its segments agree and `ring_shifts` moves them alike
    ring_build_shift: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))

    @property
    def records(self) -> Mapping:
        return self.state.records

    def impostor_shifts(self, indices) -> np.ndarray:
        """(n, 3) metres the units at `indices` have drifted since their impostors were made: their quads move
        by it."""
        if self.unit_drifts is None:
            return np.zeros((len(indices), 3))
        held = np.array([self.records[self.clouds.members[i]].drift for i in indices], dtype=np.float64)
        return self.unit_drifts[list(indices)] - held.reshape(-1, 3)

    @property
    def ring_state(self) -> RingState:
        return self.state.ring

    @property
    def predicted_ms(self) -> float:
        return self.costs.ms(self.update_work + self.cloud_work)

    def of_kind(self, *kinds: str) -> list:
        return [self.clouds[index] for index in self.clouds.indices_of(*kinds)]

    def stats(self) -> PlanStats:
        units = self.clouds
        reasons: dict = {}
        for index in sorted(units.regenerate):
            reason = units.regenerate[index]
            reasons[reason] = reasons.get(reason, 0) + 1
        split = {index: len(splits) + 1 for index, splits in units.splits.items() if splits}
        return PlanStats(
            clouds_by_kind=units.clouds_by_kind(),
            units=len(units),
            units_grouped=int(np.count_nonzero(units.member_counts > 1)),
            impostors_drawn=units.count(*TEXTURED) + units.count("inside"),
            impostors_regenerated=sum(reasons.values()),
            regeneration_reasons=reasons,
            regenerations_postponed=sum(1 for reason in units.postponed.values() if reason),
            ring_segments_built=(
                sum(1 for _, _, members in self.ring.segment_builds() if members) if self.ring is not None else 0
            ),
            ring_panels_drawn=(
                sum(len(g.occupied_segments) for g, _ in self.ring.draws) if self.ring is not None else 0
            ),
            objects_in_clouds=len(self.objects_between_layers),
            layers_drawn=sum(split.values()),
            layers_rebuilt=sum(layers for index, layers in split.items() if units.regenerate.get(index)),
            predicted_ms=self.predicted_ms,
            priced=self.priced,
            tolerance_deg=self.tolerance_deg,
            accepted_error_tolerances=self.accepted_error,
            drawn_as=self.state.drawn_as or "",
            measured_units_ms=self._measured_ms("units"),
            measured_full_ms=self._measured_ms("full"),
            costs=self.costs,
            cloud_scale=self.cloud_scale,
        )

    def _measured_ms(self, choice: str) -> float:
        time = self.state.frame_times.get(choice)
        return time.mean_ms if time is not None else 0.0

    @property
    def settled(self) -> bool:
        """Whether this plan leaves nothing to converge: no impostor remade or postponed, no crossfade
        and no ring being built or faded in.  The same inputs would then draw the same picture again;
        the editor keeps it instead (`app.viewport`), leaving the cores to the relighting worker."""
        ring_settled = self.ring is None or (
            self.ring.state.pending is None
            and not self.ring.builds  # a ring built and shown in one frame (`cloudcore.lod.ring.rebuild_frames`)
            and all(weight == 1.0 for _, weight in self.ring.draws)
        )
        units = self.clouds
        return (
            ring_settled
            and not any(units.regenerate.values())
            and not any(units.postponed.values())
            and not units.count("crossfade")
        )

    @property
    def objects_between_layers(self) -> tuple:
        """Objects drawn inside the cloud pass; the rest are drawn with the world."""
        return self.draw_items.objects
