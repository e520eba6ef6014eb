"""The frame plan: what each cloud costs this frame, decided before any GL call (pure numpy).

`plan_frame` turns (the LOD units, camera, viewport, settings, the state
carried from the last frame, the lighting, measured costs) into a
`FramePlan`.  A unit (`cloudcore.lod.units`) is a cloud, or a group of clouds
whose particles interpenetrate, drawn as one; per unit one of

- ``empty``: no particles, nothing to draw;
- ``culled``: its bounding sphere misses the view frustum: no work at all;
- ``ring``: shown by Wang's ring of impostors only;
- ``full``: every particle drawn;
- ``impostor``: a textured quad, remade when `regenerate` names a reason;
- ``crossfade``: both, weights summing to one, while auto mode moves the
  unit from one representation to the other over `transition_frames` (the
  GL side mixes the two premultiplied images linearly, so the opacity is
  right throughout);
- ``inside``: the eye is in the cloud: a screen-sized impostor at reduced
  resolution, redrawn every frame (Harris 3.1); units the eye is in at once
  that follow each other in `draw_items` share one (their particles sorted
  together, one composite over the screen),

and the `LodState` to carry into the next frame.  In auto mode the choice
between full 3D and an impostor is by predicted cost within the tolerance:
an impostor's error is bounded by the tolerance (it is remade past it) and
full 3D is the reference, so both are admissible, and the plan prices each
with the measured `CostModel` (`cloudcore.lod.costs`): full 3D its particles
and fragments, the impostor its quad plus its regeneration spread over the
frames it is predicted to last at the eye's current speed.  The screen
impostor is priced the same way against the particles drawn on the screen,
and Wang's ring against its clouds drawn each on its own (`_ring_pays`).  What
per-unit prices miss (units drawn all in full 3D are one sorted draw) is
settled by measurement: `_frame_choice` draws a frame all in full 3D where
that measured cheaper.  The GL side executes plans and nothing else;
statistics come from the plan.

Objects inside a drawn unit's bounds split it into layers
(`cloudcore.lod.splitting`); `draw_items` is then the frame's cloud pass far to
near: unit layers, and the objects between them.  Without objects in clouds
no particle is looked at.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Hashable, Mapping
from dataclasses import dataclass, field

import numpy as np

from cloudcore.camera import (
    frustum_planes,
    projection_matrix,
    spheres_in_frustum,
    spheres_within_frustum,
    splats_in_frustum,
    view_matrix,
)
from cloudcore.lod.costs import CostEstimator, CostModel, Work, quad_work, regeneration_fragments, splat_fragments
from cloudcore.lod.draw_items import DrawItems, draw_items, full_runs, inside_runs
from cloudcore.lod.impostors import (
    INSIDE_RADII,
    TRANSLATION_METRICS,
    ImpostorRecord,
    budgeted_regenerations,
    content_depth,
    detail_size_px,
    parallax_errors_deg,
    quad_half_side,
    regeneration_priority,
    regeneration_reason,
    required_size,
    screen_size_px,
    tolerance_deg_for,
)
from cloudcore.lod.ring import (
    RING_FRAME_MS,
    SEGMENT_DEG,
    SEGMENTS,
    RingPlan,
    RingState,
    plan_ring,
    ring_members,
    segment_texture_size,
)
from cloudcore.lod.splitting import layers_hold, objects_reaching
from cloudcore.lod.unit_plans import (
    CROSSFADE,
    CULLED,
    DRAWN,
    EMPTY,
    FULL,
    IMPOSTOR,
    INSIDE,
    RING,
    TEXTURED,
    UnitPlans,
    kind_codes,
)
from cloudcore.lod.units import LodUnits
from cloudcore.measure.frame_stats import PlanStats
from cloudcore.measure.overdraw import splats_in_view
from cloudcore.scene import Camera
from cloudcore.settings import RenderSettings
from cloudcore.vectors import row_lengths

#: an impostor predicted to last longer than this many frames is priced as if it lasted this long
#: (a still eye would otherwise make any regeneration free)
LONGEST_LIFETIME_FRAMES = 120.0
#: auto mode switches a unit's representation only when the other is cheaper by this fraction
#: (costs measured frame to frame wobble; without it a unit near the break-even point would flicker
#: between the two, paying for a crossfade each time)
SWITCH_MARGIN = 0.25
#: bounding radii: a unit nearer than this has its full-3D fragments counted splat by splat, clipped to the
#: screen (`cloudcore.measure.overdraw.splats_in_view`); a ball of discs overestimates a near cloud tenfold, the
#: parts of it beside and behind the eye costing nothing
NEAR_EXACT_RADII = 3.0
#: auto mode's choice between a frame of units each as priced and one all in full 3D is by the frames' measured
#: times (the cost model, fitted to what is drawn, predicts the other poorly): the frames after a switch that do
#: not count (crossfades and the ring's fade), the measured frames a choice needs, the age in frames after which
#: the other's measurement is stale, and how close its predicted time must come for the other to be tried at all
#: (a scene where full 3D is predicted four times dearer never stalls to find out)
FRAME_SETTLE_FRAMES = 16
PROBE_FRAMES = 8
MEASUREMENT_AGE_FRAMES = 300
PLAUSIBLE_RATIO = 1.5
#: a scene whose particles changed by more than this factor (another scene opened, clouds added) is measured
#: afresh
SCENE_CHANGE_RATIO = 1.25
#: the running mean of a choice's frame times weighs each new frame at least this much
FRAME_TIME_FORGETTING = 0.1


@dataclass(frozen=True)
class Representation:
    """Auto mode's choice for a unit: where it is heading and how far it has come (1 = all full 3D)."""

    target: str  # "full" or "impostor"
    full_weight: float


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
    opened: frozenset = frozenset()  # the groups of clouds planned apart (`_groups_cheaper_apart`)
    object_centres: tuple = ()  # the objects' bounding-sphere centres: which of them move
    #: the units near the eye priced splat by splat last frame, for the same view to ask again (a still eye):
    #: (units, camera, viewport, {members: (their clouds' keys, Work)}), or None
    near_work: tuple | None = None

    def measured(self, measurements, fit: bool = True) -> LodState:
        """The state with this frame's (predicted work, measured ms) pairs folded into the cost fit (unless not
        `fit`: a frame planned without prices), and their sum into the measured time of the way the frame was
        drawn (once the switch to it has settled)."""
        frame_times = self.frame_times
        total_ms = sum(ms for _, ms in measurements if math.isfinite(ms) and ms >= 0.0)
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


@dataclass(frozen=True)
class FramePlan:
    clouds: UnitPlans  # per unit, what was decided: `clouds[i]` is unit i's CloudPlan
    draw_order: tuple  # indices of the units drawn individually, far to near
    ring: RingPlan | None
    state: LodState = LodState()  # to carry into the next frame
    inside_size: tuple = (0, 0)  # the screen impostor's texture size (width, height)
    draw_items: DrawItems | None = None  # the cloud pass, far to near
    objects_with_world: tuple = ()  # visible objects outside split clouds: drawn before the cloud pass
    update_work: Work = Work()  # predicted work of the impostor updates (regenerations, ring segment)
    cloud_work: Work = Work()  # predicted work of the cloud pass
    #: whether the works above were priced: full 3D draws every unit in view whatever it costs, so it prices
    #: nothing (its works are empty and its frames fit no costs: `LodState.measured`)
    priced: bool = True
    costs: CostModel = CostModel()  # the model the plan priced its choices with
    tolerance_deg: float = 0.0  # the translation tolerance in force
    #: the largest translation error drawn, in tolerances (> 1: a budget postponed it, or auto kept Wang's ring by
    #: Wang's rules, its upkeep within the tolerance past `RING_FRAME_MS`)
    accepted_error: float = 0.0
    units: LodUnits | None = None  # the frame's units, which `clouds` index: the groups planned apart opened

    @property
    def records(self) -> Mapping:
        return self.state.records

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
            ring_segments_built=int(
                self.ring is not None
                and self.ring.state.pending is not None
                and self.ring.build_segment in self.ring.state.pending.occupied_segments
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
            self.ring.state.pending is None and all(weight == 1.0 for _, weight in self.ring.draws)
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


def plan_frame(
    units: LodUnits,
    camera: Camera,
    viewport: tuple[int, int],
    settings: RenderSettings,
    state: LodState,
    lighting_key: Hashable,
    objects=(),
    cloud_particles=None,
    costs: CostModel | None = None,
    cloud_splats=None,
) -> FramePlan:
    """Plan one frame of `units` (`cloudcore.lod.units.LodUnits`) seen by `camera`.

    `lighting_key` identifies what the particles' colours were computed from: one key for
    all clouds, or a tuple with one per cloud (the editor changes one cloud at a time, and
    only its unit's impostor is stale).  `objects` are the opaque objects' bounding spheres
    this frame (`cloudcore.objects.ObjectPose`); `cloud_particles(i)` gives cloud i's particle
    centres, asked only for units with objects inside.  `costs` prices auto mode's choices;
    by default the model `state.costs` has fitted to the frames so far.  `cloud_splats(i)` gives
    cloud i's (particle centres, radii), asked for units near the eye to count their fragments.
    """
    scene_particles = float(np.sum(units.particle_counts))
    if state.frame_times and not _comparable(state.particles, scene_particles):
        state = dataclasses.replace(state, frame_times={})  # another scene: what was measured says nothing of it
    if settings.mode == "auto" and _settled_in_full_3d(state):
        # nothing to price: the choice is by measured times, and the units' measurement is fresh
        full_plan = plan_frame(
            units,
            camera,
            viewport,
            dataclasses.replace(settings, mode="full"),
            state,
            lighting_key,
            objects,
            cloud_particles,
            costs,
            cloud_splats,
        )
        drawn = {full_plan.clouds.members[i]: Representation("full", 1.0) for i in full_plan.clouds.indices_of("full")}
        return dataclasses.replace(
            full_plan,
            state=dataclasses.replace(
                full_plan.state,
                representations=drawn,
                frame_choice=_frame_choice(state, "full", {}),  # the units are measured: no prediction is asked
                drawn_as="full",
                frames_drawn_as=state.frames_drawn_as + 1,
            ),
        )
    costs = state.costs.model() if costs is None else costs
    pricing = _pricing(camera, viewport, settings, state, objects)
    groups_may_open = settings.mode == "auto" and settings.groups_apart_in_motion and units.clouds is not None
    # the units and, where groups may be planned apart, their clouds, priced in one pass: a pass costs about
    # 0.2 ms whatever its size (the field's groups priced apart 0.72 -> 0.15 ms a frame)
    seen = _seen(units.and_clouds if groups_may_open else units, *pricing, priced=_priced(settings))
    arguments = (pricing, seen, camera, viewport, settings, state, lighting_key, objects, cloud_particles, costs)
    arguments += (cloud_splats,)
    if not groups_may_open:
        return _plan_units(units, frozenset(), *arguments)
    wanted = _groups_cheaper_apart(units, seen, settings, state, costs, pricing[4])
    held = wanted & state.opened
    plan = _plan_units(units, held, *arguments)
    # a group opens only where its own impostor is due anyway, so the switch steps no more than a regeneration
    due = frozenset(
        members
        for members in (plan.clouds.members[i] for i in {**plan.clouds.regenerate, **plan.clouds.postponed})
        if members in wanted - held
    )
    return _plan_units(units, held | due, *arguments) if due else plan


def _plan_units(
    units: LodUnits,
    opened: frozenset,
    pricing: tuple,
    seen: _Seen,
    camera: Camera,
    viewport: tuple[int, int],
    settings: RenderSettings,
    state: LodState,
    lighting_key: Hashable,
    objects,
    cloud_particles,
    costs: CostModel,
    cloud_splats,
) -> FramePlan:
    """`plan_frame` with the groups `opened` planned apart, their clouds each a unit of its own; `pricing` is
    `_pricing`'s, `seen` the `_seen` of the units (of `LodUnits.and_clouds` when groups may be opened)."""
    scene_particles = float(np.sum(units.particle_counts))
    if opened:
        rows = units.apart_rows(opened)
        units, seen = units.and_clouds.take(rows), seen.take(rows)
    else:
        seen = seen.take(slice(0, len(units.radii)))  # views: the units' own rows, first in `and_clouds`
    width, height = viewport
    priced = _priced(settings)
    eye, last_eye, translation_error, tolerance, focal_px, screen_pixels, _ = pricing
    centres, radii = units.centres, units.radii
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, width / height)
    view_projection = projection @ view
    planes = frustum_planes(view_projection)
    visible = spheres_in_frustum(planes, centres, radii)
    object_centres = np.array([o.centre for o in objects], dtype=np.float64).reshape(-1, 3)
    object_radii = np.array([o.radius for o in objects], dtype=np.float64)
    distances, ball_fragments, quad_pixels_of, lifetimes = (
        seen.distances,
        seen.ball_fragments,
        seen.quad_pixels,
        seen.lifetimes,
    )
    cloud_keys = lighting_key if isinstance(lighting_key, tuple) else (lighting_key,) * sum(map(len, units.members))

    def unit_key(index: int) -> tuple:
        """What the colours of unit `index` were computed from: its clouds' keys."""
        return tuple(cloud_keys[c] for c in units.members[index])

    records = state.records
    objects_visible = spheres_in_frustum(planes, object_centres, object_radii)
    # auto mode prices Wang's ring against drawing its clouds each as auto would (the cheaper of full 3D and
    # an impostor): a sparse far field is cheaper drawn than its panels and their rebuilds
    ring_ms = alone_ms = ring_error = 0.0
    chases_tolerance = False
    candidates = np.zeros(len(radii), dtype=bool)
    # auto mode found the last frame cheaper drawn all in full 3D (`_frame_choice`): every unit heads there
    all_full = settings.mode == "auto" and state.frame_choice == "full"
    # per unit, its full-3D work far off (particles, fragments): splat by splat for the ring's candidates in view
    in_view_particles, in_view_fragments = units.particle_counts.astype(np.float64), ball_fragments.copy()
    if settings.mode == "auto" and settings.uses_ring:
        candidates = ring_members(centres, radii, eye, settings)
        step = eye - last_eye if last_eye is not None else np.zeros(3)
        alone = candidates & visible
        ring_panels, ring_rebuild, moved_lifetime, tolerance_lifetime = _ring_work(
            units,
            candidates,
            centres,
            eye,
            step,
            ball_fragments,
            quad_pixels_of[alone],
            lifetimes,
            settings,
            state.ring,
        )
        # the ring is kept within the tolerance (rebuilt once a cloud of it passes it: Wang's panels are impostors
        # too) while that costs at most its share of a frame; past it, only by Wang's own rules, as impostor mode
        # does, and the error it then shows is the plan's accepted error (the 1.2M field orbiting 0.05 degrees a
        # frame: 18 ms a frame of rebuilds to keep it so, 1.1 s every 60 frames, for 1.2 dB)
        chases_tolerance = costs.ms(ring_rebuild) / max(tolerance_lifetime, 1.0) <= RING_FRAME_MS
        ring_lifetime = tolerance_lifetime if chases_tolerance else moved_lifetime
        ring_ms = costs.ms(ring_panels + ring_rebuild.scaled(1.0 / max(ring_lifetime, 1.0)))
        ring_error = _ring_error(state.ring.current, translation_error, eye)
        if units.sample is not None:
            in_view_particles[alone], in_view_fragments[alone] = _in_view_work(
                units, alone, planes, eye, focal_px, screen_pixels, ball_fragments
            )
        in_view = (in_view_particles[alone], in_view_fragments[alone])
        alone_ms = _alone_ms(units, seen, alone, in_view, focal_px, settings, costs)
        # a candidate drawn on its own until a ring being built takes it: an impostor made for it now lasts only
        # that long (Harris's circle at 800 clouds made 136 impostors in its first frame for a ring in 16 frames)
        lifetimes = np.where(candidates, np.minimum(lifetimes, _frames_until_ring(state.ring, settings)), lifetimes)
    ring = plan_ring(
        state.ring,
        centres,
        radii,
        eye,
        settings,
        cloud_keys,
        units.members,
        units.member_set,
        segment_texture_size(height, camera.fov_y_deg, settings),
        holds_clouds=settings.mode != "auto" or (not all_full and _ring_pays(state.ring, ring_ms, alone_ms)),
        past_tolerance=chases_tolerance and ring_error > tolerance,
        # a segment is priced as its update is (below), by its particles: what the segment's render takes on
        # llvmpipe (478,000 particles of the 1.2M field, 368 ms: 0.77 us a particle, the fit's prior 0.85)
        build_ms=lambda members: costs.particles * float(units.particle_counts[units.row_of[members]]),
    )

    def particles_of(index: int) -> np.ndarray:
        members = units.members[index]
        if len(members) == 1:
            return cloud_particles(members[0])
        return np.concatenate([cloud_particles(c) for c in members])

    def splats_of(index: int) -> tuple[np.ndarray, np.ndarray]:
        """The unit's particles' (centres, radii), of `cloud_splats`."""
        members = units.members[index]
        if len(members) == 1:
            return cloud_splats(members[0])
        splats = [cloud_splats(c) for c in members]
        return np.concatenate([c for c, _ in splats]), np.concatenate([r for _, r in splats])

    # most scenes have no objects: split_at is asked for every unit drawn, hundreds as a field's ring fades
    reaching = (
        objects_reaching(centres, radii, object_centres, object_radii)
        if settings.split_objects and len(object_radii)
        else None
    )
    # and most units hold none: a set answers for them without numpy (45 units a frame along the flythrough)
    holding = frozenset(np.flatnonzero(np.any(reaching, axis=1)).tolist()) if reaching is not None else frozenset()

    def split_at(index: int, from_eye) -> tuple[tuple, tuple]:
        """(objects inside the unit far to near from `from_eye`, their distances: the layers' boundaries)."""
        if index not in holding:
            return (), ()
        inside = np.flatnonzero(reaching[index])
        gaps = np.linalg.norm(object_centres[inside] - np.asarray(from_eye, dtype=np.float64), axis=1)
        order = np.argsort(-gaps, kind="stable")
        return tuple(int(i) for i in inside[order]), tuple(float(g) for g in gaps[order])

    def layers_changed(index: int, record: ImpostorRecord) -> bool:
        """Whether the objects inside the unit would now cut the layers of its impostor `record` otherwise."""
        inside, _ = split_at(index, record.eye)
        if inside != record.split_objects:
            return True
        if not inside:
            return False
        if cloud_splats is None:  # only the particles' centres: points
            particles = particles_of(index)
            particle_radii = np.zeros(len(particles))
        else:
            particles, particle_radii = splats_of(index)
        cut = list(inside)
        return not layers_hold(
            particles, particle_radii, record.eye, object_centres[cut], object_radii[cut], record.splits
        )

    held_near = state.near_work
    known_near = (
        held_near[3] if held_near and held_near[0] is units and held_near[1:3] == (camera, tuple(viewport)) else {}
    )
    near_work = {}  # members -> (keys, Work) of the units priced splat by splat this frame

    def full_3d(index: int, radius: float, distance: float) -> Work:
        """The unit drawn in full 3D: a ball of discs far off; near, splat by splat, only the splats in the
        frustum (the renderer leaves out the rest), their discs clipped to the screen; a still eye's again
        from last frame (auto mode's plan of the default view 4.65 -> 3.2 ms, best of 40)."""
        if not priced:
            return Work()
        if cloud_splats is None or distance >= NEAR_EXACT_RADII * radius:
            return Work(particles=float(units.particle_counts[index]), fragments=float(ball_fragments[index]))
        members = units.members[index]
        held = known_near.get(members)
        if held is not None and held[0] == unit_key(index):
            near_work[members] = held
            return held[1]
        kept, overdraw = splats_in_view(*splats_of(index), view, projection)
        work = Work(particles=float(kept), fragments=screen_pixels * overdraw)
        near_work[members] = (unit_key(index), work)
        return work

    representations = {}
    update_work, cloud_work = Work(), Work()
    # auto mode weighs the frame as planned unit by unit against every unit in full 3D in one sorted draw: splitting
    # the particles into many draws between impostors costs what no unit's own price shows
    individuals = 1.0 - (ring.weights(units.members, units.row_of) if ring is not None else np.zeros(len(radii)))
    in_ring = (individuals <= 0.0) & (radii > 0.0) & visible
    everything_full = Work(
        particles=float(np.sum(in_view_particles[in_ring])),
        fragments=float(np.sum(in_view_fragments[in_ring])),
        batches=1.0,
    )
    unit_prices = []
    wanted = []  # (index, priority, work) of the impostors past their tolerance
    # what the plan decides per unit, as arrays (`UnitPlans`): a unit out of view or in the ring is one row
    count = len(radii)
    kinds = np.where(radii <= 0.0, EMPTY, np.where(individuals <= 0.0, RING, CULLED)).astype(np.int8)
    full_weights, impostor_weights = np.zeros(count), np.zeros(count)
    texture_sizes = np.zeros(count, dtype=np.int64)
    full_prices, impostor_prices = np.zeros(count), np.zeros(count)
    reasons, split_objects, split_distances = {}, {}, {}
    drawable = np.flatnonzero((radii > 0.0) & (individuals > 0.0) & visible)
    # the impostors kept are those of the units the ring does not show whole: a unit in the ring is drawn by its
    # panel, and when the ring hands it back the eye has moved a rebuild's distance (15% of the ring's radius),
    # past the tolerance of all but the largest clouds; its texture is freed meanwhile (at Harris's scale, a
    # flight kept thousands)
    next_records = {
        members: record
        for members, record in records.items()
        if members in units.row_of and individuals[units.row_of[members]] > 0.0
    }
    held_errors = _held_errors(units, drawable, records, translation_error, eye) if settings.mode != "full" else None
    may_be_textured = visible & (radii > 0.0) & (individuals > 0.0) & (distances >= INSIDE_RADII * radii)
    textured = (
        _impostor_textures(units, np.flatnonzero(may_be_textured), distances, height, camera.fov_y_deg, settings)
        if settings.mode != "full"
        else {}
    )

    def decided(index: int, kind: int, inside: tuple, splits: tuple, full_weight=0.0, full_ms=0.0, impostor_ms=0.0):
        """Unit `index` drawn as `kind`, split around the objects `inside` it at `splits`."""
        kinds[index], full_weights[index] = kind, full_weight
        full_prices[index], impostor_prices[index] = full_ms, impostor_ms
        if splits:
            split_objects[index], split_distances[index] = inside, splits

    if settings.mode == "full":
        # every unit in view in full 3D, nothing priced: only the units holding objects are looked at one by one
        kinds[drawable], full_weights[drawable] = FULL, 1.0
        for index in sorted(holding.intersection(drawable.tolist())):
            decided(index, FULL, *split_at(index, eye), full_weight=1.0)
        drawable = ()
    for index in drawable:
        index = int(index)
        radius, distance, members = radii[index], float(distances[index]), units.members[index]
        individual = float(individuals[index])
        inside, splits = split_at(index, eye)
        eye_inside = distance < INSIDE_RADII * radius
        # impostor mode draws no unit in full 3D but the one the eye is in: nothing else to price
        full = full_3d(index, radius, distance) if settings.mode != "impostor" or eye_inside else Work()
        everything_full += full
        if eye_inside:
            # a screen impostor has fewer fragments than the screen, not fewer particles; its composite
            # over the screen is priced per run of inside units, below (here, for the choice, as one each)
            screen_impostor = dataclasses.replace(full, fragments=full.fragments * settings.inside_resolution_scale**2)
            full_ms, inside_ms = (
                costs.ms(full),
                costs.ms(screen_impostor + Work(quad_pixels=screen_pixels, quads=1, batches=1)),
            )
            if settings.mode == "auto" and individual == 1.0:
                previous = state.representations.get(members)
                held = previous.target if previous is not None and previous.full_weight == 1.0 else None
                # the same particles either way
                target = "full" if all_full else _cheapest(held, {"full": full_ms, "inside": inside_ms})
                unit_prices.append((index, distance, full_ms, inside_ms))
                representations[members] = Representation(target, 1.0)
                if target == "full":
                    decided(index, FULL, inside, splits, 1.0, full_ms, inside_ms)
                    cloud_work += full
                    continue
            decided(index, INSIDE, inside, splits, individual, full_ms, inside_ms)
            cloud_work += screen_impostor
            continue
        pixels, size, remake = textured[index]
        quad = quad_work(pixels, screen_pixels)
        # a unit fading into or out of the ring is drawn as an impostor: one layer scales exactly
        weight, full_ms, impostor_ms = 0.0, costs.ms(full), math.inf
        if settings.mode == "auto" and individual == 1.0:
            lifetime = float(lifetimes[index])
            impostor_ms = costs.ms(quad) + costs.ms(remake.scaled(len(splits) + 1)) / max(lifetime, 1.0)
            error = float(held_errors[index])
            budgeted = bool(settings.regeneration_budget or settings.frame_budget_ms)
            # an impostor within half its tolerance of the picture full 3D gives, or one remade from this very
            # eye, differs from it by less than a regeneration's own step: the switch needs no crossfade
            close = {
                "impostor": error <= 0.5 * tolerance or (error > tolerance and not budgeted),
                "full": error <= 0.5 * tolerance,
            }
            representation = _represent(
                state.representations.get(members),
                full_ms,
                math.inf if all_full else impostor_ms,
                settings.transition_frames,
                close,
            )
            unit_prices.append((index, distance, full_ms, impostor_ms))
            representations[members] = representation
            weight = representation.full_weight
        if weight == 1.0:
            decided(index, FULL, inside, splits, 1.0, full_ms, impostor_ms)
            cloud_work += full
            continue
        record = records.get(members)
        reason = regeneration_reason(
            record,
            size,
            unit_key(index),
            tolerance,
            float(held_errors[index]),
            record is not None and layers_changed(index, record),
        )
        kind = CROSSFADE if weight > 0.0 else IMPOSTOR
        decided(index, kind, inside, splits, weight * individual, full_ms, impostor_ms)
        impostor_weights[index], texture_sizes[index] = (1.0 - weight) * individual, size
        if reason is not None:
            reasons[index] = reason
        cloud_work += quad + (full + Work(quad_pixels=screen_pixels) if weight > 0.0 else Work())  # the layer
        if reason is not None:
            ratio = float(held_errors[index]) / max(tolerance, 1e-300)
            wanted.append(
                (index, regeneration_priority(reason, ratio, bool(splits), pixels), remake.scaled(len(splits) + 1))
            )
    served = budgeted_regenerations([(index, priority) for index, priority, _ in wanted], settings.regeneration_budget)
    if settings.frame_budget_ms > 0.0:
        served &= _within_frame_budget(wanted, settings.frame_budget_ms - costs.ms(cloud_work), costs)
    for index, _, remake in wanted:
        if index in served:
            update_work += remake
    # the largest translation error drawn, over the tolerance
    accepted = 0.0 if chases_tolerance or ring is None or not ring.draws else ring_error / max(tolerance, 1e-300)
    regenerate, postponed = {}, {}
    for index in np.flatnonzero(np.isin(kinds, kind_codes(*TEXTURED))).tolist():
        members = units.members[index]
        record = records.get(members)
        if index not in served and record is not None:
            accepted = max(accepted, float(held_errors[index]) / max(tolerance, 1e-300))
        if index in served:
            record = next_records[members] = ImpostorRecord(
                tuple(float(v) for v in eye),
                int(texture_sizes[index]),
                unit_key(index),
                split_distances.get(index, ()),
                split_objects.get(index, ()),
                content_depth(centres[index], radii[index], eye, *splats_of(index)) if cloud_splats else None,
            )
        reason = reasons.get(index)
        if reason is not None:
            (regenerate if index in served else postponed)[index] = reason
        texture_sizes[index] = record.size
    if ring is not None:
        for generation, _ in ring.draws:
            rows = generation.rows_in(units.members, units.row_of)
            shown = rows[visible[rows]]
            cloud_work += _ring_panels_work(len(generation.occupied_segments), quad_pixels_of[shown])
        piece = ring.build_members
        update_work += Work(
            particles=float(sum(units.particle_counts[units.row_of[u]] for u in piece)),
            regenerations=float(bool(piece)),
        )
    plans = UnitPlans(
        kinds,
        distances,
        units.members,
        units.member_counts,
        full_weights,
        impostor_weights,
        texture_sizes,
        full_prices,
        impostor_prices,
        regenerate,
        postponed,
        split_objects,
        split_distances,
    )
    drawn = np.flatnonzero(np.isin(kinds, kind_codes(*DRAWN)))
    draw_order = tuple(drawn[np.argsort(-distances[drawn], kind="stable")].tolist())
    inside_size = tuple(max(1, math.ceil(side * settings.inside_resolution_scale)) for side in viewport)
    items = draw_items(plans, draw_order, radii, object_centres, objects_visible, eye)
    screen_impostors = len(inside_runs(items, plans))
    cloud_work += Work(
        batches=float(full_runs(kinds[list(draw_order)]) + screen_impostors),
        quad_pixels=screen_impostors * screen_pixels,
        quads=float(screen_impostors),
    )
    between = set(items.objects)
    with_world = tuple(i for i in range(len(object_radii)) if objects_visible[i] and i not in between)
    drawn_as = frame_choice = None
    if settings.mode == "auto":
        drawn_as = "full" if all_full else "units"
        predicted = {
            "units": _units_ms(unit_prices, ring_ms, alone_ms, candidates, costs),
            "full": costs.ms(everything_full),
        }
        frame_choice = _frame_choice(state, drawn_as, predicted)
    next_state = LodState(
        next_records,
        ring.state if ring is not None else RingState(),
        representations,
        tuple(float(v) for v in eye),
        state.costs,
        frame_choice,
        drawn_as,
        state.frames_drawn_as + 1 if state.drawn_as == drawn_as else 1,
        state.frame_index + 1,
        state.frame_times,
        scene_particles,
        opened,
        tuple(tuple(float(v) for v in centre) for centre in object_centres),
        (units, camera, tuple(viewport), near_work) if near_work else None,
    )
    return FramePlan(
        plans,
        draw_order,
        ring,
        next_state,
        inside_size,
        items,
        with_world,
        update_work if priced else Work(),
        cloud_work if priced else Work(),
        priced,
        costs,
        tolerance,
        accepted,
        units,
    )


def _impostor_textures(units: LodUnits, rows, distances, height: int, fov_y_deg: float, settings) -> dict:
    """Per unit of `rows`, (its quad's side on the screen in pixels, its impostor texture's side, the `Work` of
    remaking it: every particle splatted into that texture), the fragments in one numpy pass (unit by unit, numpy's
    overhead was 30 us a unit; the field's plan 5.06 -> 4.65 ms)."""
    pixels, sizes, half_sides = [], [], []
    for index in rows:
        radius, distance = float(units.radii[index]), float(distances[index])
        side = screen_size_px(radius, distance, height, fov_y_deg)
        detail = detail_size_px(radius, distance, units.finest_radii[index], settings.impostor_detail_texels)
        pixels.append(side)
        sizes.append(required_size(min(side, detail), settings.impostor_min_size, settings.impostor_max_size))
        half_sides.append(quad_half_side(radius, distance))
    counts = units.particle_counts[rows]
    fragments = regeneration_fragments(
        counts, units.radius_squares[rows], units.radii[rows], distances[rows], np.array(half_sides), np.array(sizes)
    )
    return {
        int(index): (side, size, Work(particles=float(count), texture_fragments=float(f), regenerations=1.0))
        for index, side, size, count, f in zip(rows, pixels, sizes, counts, np.reshape(fragments, -1))
    }


def _units_ms(unit_prices, ring_ms: float, alone_ms: float, candidates, costs: CostModel) -> float:
    """The predicted time of a frame of units each in the representation its own price picks.

    The units' prices (`unit_prices`: (index, distance, full 3D ms, the other's ms) of the units planned
    on their own) miss that full units between impostors are drawn in as many batches as there are
    runs; the ring's candidates in view (`candidates`) count as the cheaper of the ring (`ring_ms`)
    and their own prices (`alone_ms`).
    """
    priced_ms, kinds = 0.0, []
    for index, _, full_ms, other_ms in sorted(unit_prices, key=lambda price: -price[1]):
        if not candidates[index]:
            priced_ms += min(full_ms, other_ms)
        kinds.append(FULL if full_ms <= other_ms else IMPOSTOR)
    ring_part = min(ring_ms, alone_ms) if candidates.any() else 0.0
    return priced_ms + ring_part + costs.batches * full_runs(np.array(kinds, dtype=np.int8))


def _comparable(before: float, now: float) -> bool:
    """Whether a scene of `now` particles is the one of `before` for what was measured of it."""
    return before > 0.0 and now > 0.0 and max(before, now) <= SCENE_CHANGE_RATIO * min(before, now)


def _known(state: LodState, choice: str) -> bool:
    """Whether the frames drawn as `choice` have been measured for long enough, recently enough, to choose by."""
    time = state.frame_times.get(choice)
    frame = state.frame_index + 1  # the frame being planned
    return time is not None and time.frames >= PROBE_FRAMES and frame - time.last_frame <= MEASUREMENT_AGE_FRAMES


def _priced(settings: RenderSettings) -> bool:
    """Whether the plan prices its units: full 3D draws every unit in view whatever it costs, so it does not."""
    return settings.mode != "full"


def _settled_in_full_3d(state: LodState) -> bool:
    """Auto mode draws every unit in full 3D, settled there, and has measured the units' way freshly: the frame
    can be planned as full mode plans it, without pricing a unit."""
    return (
        state.frame_choice == state.drawn_as == "full"
        and state.frames_drawn_as > FRAME_SETTLE_FRAMES
        and _known(state, "units")
    )


def _frame_choice(state: LodState, drawn_as: str, predicted: dict) -> str:
    """How auto mode draws the next frame: "units" or "full" (`LodState.frame_choice`), by the measured times
    of both (`_cheapest`, within its margin), once both are measured and fresh; the way this frame was drawn
    while it is being measured; the other, to measure it, where its `predicted` time is plausibly close.
    The choice acts through each unit's representation and the ring, so a switch crossfades."""
    other = "full" if drawn_as == "units" else "units"
    if not _known(state, drawn_as):
        return drawn_as
    if _known(state, other):
        return _cheapest(drawn_as, {choice: state.frame_times[choice].mean_ms for choice in (drawn_as, other)})
    return other if predicted[other] < PLAUSIBLE_RATIO * predicted[drawn_as] else drawn_as


def _frames_until_ring(state: RingState, settings: RenderSettings) -> float:
    """Frames until the ring being built (or, with none yet, the first, begun this frame) shows its clouds
    whole: its segments left, one a frame, then its fade (inf: no ring holding clouds is on its way)."""
    if state.current is None and state.pending is None:
        return float(SEGMENTS + settings.ring_fade_frames)
    if state.pending is None or not state.pending.holds_clouds:
        return math.inf
    return float(SEGMENTS - state.built + settings.ring_fade_frames - state.fade_step)


def _ring_panels_work(panels: int, quad_pixels) -> Work:
    """Drawing `panels` ring panels (each a draw call) holding clouds whose own impostor quads would fill
    `quad_pixels` on the screen: a panel is cropped to its clouds' extent, so it fills about what they would."""
    return Work(quad_pixels=float(np.sum(quad_pixels)), quads=float(panels))


def _ring_work(
    units: LodUnits, candidates, centres, eye, step, ball_fragments, quad_pixels, lifetimes, settings, state: RingState
) -> tuple[Work, Work, float, float]:
    """(panels, rebuild, moved, tolerated): Wang's ring holding the units `candidates` (mask).

    Its panels drawn a frame (`quad_pixels`: the candidates in view's impostor quads), its rebuild (every
    candidate splatted into the segments, whose textures have the screen's pixel density), and the frames
    it lasts: until the eye's current `step` a frame carries it past a rebuild distance, or the frames the
    last ring lasted when shorter (moved); and that or the frames its clouds' impostors would (`lifetimes`),
    when shorter still (tolerated).
    """
    offsets = centres[candidates] - eye
    azimuths = np.degrees(np.arctan2(offsets[:, 0], -offsets[:, 2])) % 360.0
    panels = len(np.unique(np.floor(azimuths / SEGMENT_DEG)))
    horizontal, vertical = math.hypot(step[0], step[2]), abs(step[1])
    moved = min(
        LONGEST_LIFETIME_FRAMES,
        state.rebuild_interval,
        settings.ring_rebuild_horizontal * settings.ring_radius / max(horizontal, 1e-300),
        settings.ring_rebuild_vertical * settings.ring_radius / max(vertical, 1e-300),
    )
    rebuild = Work(
        particles=float(np.sum(units.particle_counts[candidates])),
        texture_fragments=float(np.sum(ball_fragments[candidates])),
        regenerations=float(panels),
    )
    tolerated = min(moved, float(np.min(lifetimes[candidates], initial=math.inf)))
    return _ring_panels_work(panels, quad_pixels), rebuild, moved, tolerated


def _in_view_work(units: LodUnits, chosen, planes, eye, focal_px, screen_pixels, ball_fragments):
    """(particles, fragments) per unit of `chosen` (mask) drawn in full 3D far from the eye.

    A unit wholly in the frustum has all its splats in view, a ball of discs (`ball_fragments`); one its
    planes cut (a cloud field's far units are kilometres across, and partly out of view) is counted splat by
    splat, only the splats in the frustum, each a disc of pi (f r / z)^2 at most the screen, over the units'
    `SplatSample`: the 1.2M-particle field's 416 candidates took 65 ms a frame counted splat by splat, every
    one, 0.3 with the sample and the shortcut.
    """
    indices = np.flatnonzero(chosen)
    particles = units.particle_counts[indices].astype(np.float64)
    fragments = np.asarray(ball_fragments, dtype=np.float64)[indices]
    cut = np.flatnonzero(~spheres_within_frustum(planes, units.centres[indices], units.radii[indices]))
    particles[cut] = fragments[cut] = 0.0
    clouds = [cloud for owner in cut for cloud in units.members[indices[owner]]]
    if not clouds:
        return particles, fragments
    owners = [owner for owner in cut for _ in units.members[indices[owner]]]
    owners, centres, radii, weights = units.sample.of_clouds(clouds, owners)
    seen = np.flatnonzero(splats_in_frustum(planes, centres, radii))
    owners, centres, radii, weights = owners[seen], centres[seen], radii[seen], weights[seen]
    offsets = centres - eye
    depths = np.maximum(row_lengths(offsets), radii)
    discs = np.minimum(math.pi * np.square(focal_px * radii / depths), screen_pixels)
    count = len(indices)
    particles += np.bincount(owners, weights=weights, minlength=count)
    fragments += np.bincount(owners, weights=weights * discs, minlength=count)
    return particles, fragments


def _alone_ms(units: LodUnits, seen: _Seen, chosen, in_view, focal_px, settings, costs) -> float:
    """The units `chosen` (mask) drawn each on its own as auto mode would, far from the eye: per unit the
    cheaper of full 3D (`in_view`: its particles and fragments in view) and an impostor (`_impostor_ms`)."""
    full = costs.particles * in_view[0] + costs.fragments * in_view[1]
    return float(np.sum(np.minimum(full, _impostor_ms(units, seen, chosen, focal_px, settings, costs))))


@dataclass(frozen=True)
class _Seen:
    """What the plan prices units by, per unit, from this frame's eye."""

    distances: np.ndarray  # of the centre from the eye
    ball_fragments: np.ndarray  # of full 3D, its splats a ball of discs (`splat_fragments`)
    half_sides: np.ndarray  # of the impostor quad through the centre, metres
    quad_pixels: np.ndarray  # of the impostor quad on the screen (all of it with the eye inside)
    #: frames an impostor made now lasts at the eye's speed (and an object's moving inside it), at most
    #: LONGEST_LIFETIME_FRAMES
    lifetimes: np.ndarray
    layers: np.ndarray  # textures of the impostor: one more than the objects inside

    def take(self, rows) -> _Seen:
        """What is seen of the units at `rows`."""
        return _Seen(*(getattr(self, field.name)[rows] for field in dataclasses.fields(self)))


def _seen(
    units: LodUnits,
    eye,
    last_eye,
    translation_error,
    tolerance: float,
    focal_px,
    screen_pixels,
    objects,
    priced: bool = True,
) -> _Seen:
    """`objects`: (centres, radii, depth steps) of the objects that split units into layers (none when not
    split), the steps how far each moved in depth since last frame.  Not `priced` (full 3D), only the
    distances: every price zero."""
    centres, radii = units.centres, units.radii
    distances = np.linalg.norm(centres - eye, axis=1)
    if not priced:
        nothing = np.zeros(len(radii))
        return _Seen(distances, nothing, nothing, nothing, nothing, nothing + 1.0)
    # the translation error of one frame at the eye's current speed
    rates = translation_error(centres, radii, last_eye, eye) if last_eye is not None else np.zeros(len(radii))
    object_centres, object_radii, depth_steps = objects
    reach = np.linalg.norm(centres[:, None] - object_centres[None], axis=2) < radii[:, None] + object_radii[None]
    reach &= (radii > 0.0)[:, None]
    # an object moving in depth inside a unit remakes its layers once it passes a particle it covers
    # (`cloudcore.lod.splitting.layers_hold`): about every 2R / m metres of depth, m of the unit's particles
    # overlapping it on screen, their share the area of a disc of its radius plus a typical particle's over the unit's
    typical_radii = np.sqrt(units.radius_squares / np.maximum(units.particle_counts, 1.0))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        covered_shares = np.minimum(((object_radii[None] + typical_radii[:, None]) / radii[:, None]) ** 2, 1.0)
        spacings = 2.0 * radii[:, None] / np.maximum(units.particle_counts[:, None] * covered_shares, 1.0)
        split_lifetimes = np.nan_to_num(spacings / depth_steps[None], nan=math.inf)
    split_lifetimes = np.min(np.where(reach, split_lifetimes, math.inf), axis=1, initial=math.inf)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # the eye inside: the whole screen
        half_sides = radii * distances / np.sqrt(np.maximum((distances - radii) * (distances + radii), 1e-300))
        quad_pixels = np.nan_to_num(
            np.minimum((2.0 * focal_px * half_sides / distances) ** 2, screen_pixels), nan=screen_pixels
        )
    return _Seen(
        distances,
        splat_fragments(units.radius_squares, radii, distances, focal_px, units.particle_counts, screen_pixels),
        half_sides,
        quad_pixels,
        np.minimum.reduce(
            [
                np.divide(tolerance, rates, out=np.full(len(radii), math.inf), where=rates > 0.0),
                split_lifetimes,
                np.full(len(radii), LONGEST_LIFETIME_FRAMES),
            ]
        ),
        1.0 + np.count_nonzero(reach, axis=1),
    )


def _pricing(camera: Camera, viewport, settings, state: LodState, objects) -> tuple:
    """What `_seen` prices units from this frame: (eye, last frame's eye or None, the translation metric, the
    tolerance in degrees, the focal length in pixels, the screen's pixels, the objects that split units into
    layers: (centres, radii, depth steps; `_seen`), none unless `split_objects`)."""
    width, height = viewport
    centres = np.array([o.centre for o in objects], dtype=np.float64).reshape(-1, 3)
    radii = np.array([o.radius for o in objects], dtype=np.float64)
    last = np.array(state.object_centres, dtype=np.float64).reshape(-1, 3)
    eye = np.asarray(camera.position, dtype=np.float64)
    # how far each object moved in depth since last frame (inf with no last frame: as if it had jumped)
    depth_steps = (
        np.abs(np.linalg.norm(centres - eye, axis=1) - np.linalg.norm(last - eye, axis=1))
        if len(last) == len(radii)
        else np.full(len(radii), np.inf)
    )
    none = (np.zeros((0, 3)), np.zeros(0), np.zeros(0))
    splitting = (centres, radii, depth_steps) if settings.split_objects else none
    return (
        eye,
        None if state.eye is None else np.asarray(state.eye, dtype=np.float64),
        TRANSLATION_METRICS[settings.translation_metric],
        tolerance_deg_for(settings, camera.fov_y_deg, height),
        0.5 * height / math.tan(math.radians(camera.fov_y_deg) / 2.0),
        float(width * height),
        splitting,
    )


def _held_errors(units: LodUnits, drawable, records: Mapping, translation_error, eye) -> np.ndarray:
    """Per unit, the translation error of the impostor held (inf: none), measured for the units `drawable` (the
    rest are not drawn on their own: out of view, or in the ring); the parallax between the near and far points
    of what it holds (`ImpostorRecord.content`) where the record has them."""
    rows = [row for row in drawable.tolist() if units.members[row] in records]
    errors = np.full(len(units.members), math.inf)
    if not rows:
        return errors
    held = [records[units.members[index]] for index in rows]
    centres, radii = units.centres[rows], units.radii[rows]
    if translation_error is parallax_errors_deg:
        centres = np.array([c if h.content is None else h.content[0] for c, h in zip(centres, held)], dtype=np.float64)
        radii = np.array([r if h.content is None else h.content[1] for r, h in zip(radii, held)], dtype=np.float64)
    eyes = np.array([record.eye for record in held], dtype=np.float64)
    errors[rows] = np.nan_to_num(translation_error(centres, radii, eyes, eye), nan=math.inf)
    return errors


def _impostor_ms(units: LodUnits, seen: _Seen, chosen, focal_px, settings, costs: CostModel) -> np.ndarray:
    """Per unit of `chosen` (a mask or indices), its impostor a frame: the quad, and the regeneration (every
    particle, into a texture as fine as the screen or the unit's detail asks) over the impostor's lifetime."""
    half_sides, distances, fragments = seen.half_sides[chosen], seen.distances[chosen], seen.ball_fragments[chosen]
    with np.errstate(divide="ignore", invalid="ignore"):
        sides = 2.0 * focal_px * half_sides / distances
        detail = 2.0 * settings.impostor_detail_texels * half_sides / units.finest_radii[chosen]
        detail = np.where(settings.impostor_detail_texels > 0.0, detail, np.inf)
        texture = np.clip(np.minimum(sides, detail), settings.impostor_min_size, settings.impostor_max_size)
        texture_fragments = fragments * np.nan_to_num((texture / sides) ** 2, nan=1.0)
    remake = seen.layers[chosen] * (
        costs.particles * units.particle_counts[chosen]
        + costs.texture_fragments * texture_fragments
        + costs.regenerations
    )
    return costs.quad_pixels * seen.quad_pixels[chosen] + costs.quads + remake / np.maximum(seen.lifetimes[chosen], 1.0)


def _groups_cheaper_apart(units: LodUnits, seen: _Seen, settings, state: LodState, costs, focal_px: float) -> frozenset:
    """The groups of interpenetrating clouds (their members) that auto mode would rather plan apart, each cloud a
    unit of its own (`LodUnits.apart_rows`): while the eye moves, those whose clouds' impostors cost less than the
    group's (`_cheapest`, held apart while so).

    A group's impostor is the picture without the blobs of clouds sorted whole (`cloudcore.lod.units`); a
    moving eye remakes it every particle at a time, and sooner than its clouds' (its sphere is larger: more
    parallax for the same step).  Moving, the blobs are the price of the time saved (`RenderSettings.
    groups_apart_in_motion`); still (the group's impostor would outlast `LONGEST_LIFETIME_FRAMES`), or with
    the eye in its sphere, a group is whole, whatever the prices: it closes, remade from that very eye.
    `plan_frame` opens a group only where its own impostor is due anyway.  `seen`: the `_seen` of
    `units.and_clouds`.
    """
    rows = units.group_rows
    groups, group_seen = units.take(rows), seen.take(rows)
    # a group whose sphere holds the eye is whole: its screen impostor draws its particles sorted together, as
    # full 3D does, and apart its clouds would cost as much (the particles near the eye are the screen
    # impostor's cost, whatever holds them; under a stratocumulus deck apart was 1.7 times dearer)
    outside = group_seen.distances >= INSIDE_RADII * groups.radii
    moving = group_seen.lifetimes < LONGEST_LIFETIME_FRAMES
    candidates = outside & moving
    if not candidates.any():  # a still eye: nothing more to price
        return frozenset()
    part_seen = seen.take(slice(len(units.members), None))
    group_ms = _impostor_ms(groups, group_seen, candidates, focal_px, settings, costs)
    # (a cloud whose own sphere holds the eye is priced as a quad over the whole screen: dear, so its group stays)
    part_prices = _impostor_ms(units.clouds, part_seen, slice(None), focal_px, settings, costs)
    part_ms = dict(zip((members[0] for members in units.clouds.members), part_prices))
    wanted = set()
    for index, group_price in zip(np.flatnonzero(candidates), group_ms):
        members = groups.members[index]
        prices = {"group": float(group_price), "apart": sum(part_ms[cloud] for cloud in members)}
        if _cheapest("apart" if members in state.opened else "group", prices) == "apart":
            wanted.add(members)
    return frozenset(wanted)


def _ring_error(generation, translation_error, eye) -> float:
    """The largest translation error of a cloud of the ring `generation` (None: no ring; 0: none) seen from
    `eye`: Wang's panels are impostors too."""
    if generation is None or not generation.members:
        return 0.0
    centres, radii = generation.spheres
    return float(np.max(translation_error(centres, radii, generation.eye, eye), initial=0.0))


def _ring_pays(state: RingState, ring_ms: float, alone_ms: float) -> bool:
    """Whether the ring should hold its clouds: the cheaper of the two (`_cheapest`: each switch rebuilds
    the ring and crossfades it)."""
    newest = state.pending or state.current
    held = None if newest is None else "ring" if newest.holds_clouds else "alone"
    return _cheapest(held, {"ring": ring_ms, "alone": alone_ms}) == "ring"


def _within_frame_budget(wanted, available_ms: float, costs: CostModel) -> set:
    """The wanted regenerations (index, priority, work) that fit in `available_ms`, most urgent first;
    those that must be made (rank 0: nothing to show, or layers that would cut an object) always, and
    the most urgent one at least: a budget below the frame's other work slows the picture's
    convergence (after a relight, say) but never stops it."""
    served, spent = set(), 0.0
    for index, priority, work in sorted(wanted, key=lambda w: w[1]):
        ms = costs.ms(work)
        if priority[0] == 0 or spent + ms <= available_ms or not served:
            served.add(index)
            spent += ms
    return served


def _represent(
    previous: Representation | None, full_ms: float, impostor_ms: float, transition_frames: int, close: dict
) -> Representation:
    """Auto mode's next step for a unit: aim at the cheaper representation (by `SWITCH_MARGIN` against the
    one aimed at already), and move the full-3D weight one transition step toward it.

    A unit seen for the first time starts at its target: there is nothing on screen to pop from; nor
    does a switch to a representation that `close` says shows the same picture within half the
    tolerance: it is made at once, and only a switch that would show a step crossfades.
    """
    prices = {"full": full_ms, "impostor": impostor_ms}
    if previous is None:
        cheaper = _cheapest(None, prices)
        return Representation(cheaper, 1.0 if cheaper == "full" else 0.0)
    if previous.target == "inside":  # the eye has left the unit: its particles were on screen
        previous = Representation("full", 1.0)
    target = _cheapest(previous.target, prices)
    if target != previous.target and close[target] and previous.full_weight in (0.0, 1.0):
        return Representation(target, 1.0 if target == "full" else 0.0)
    step = 1.0 / transition_frames
    weight = min(1.0, previous.full_weight + step) if target == "full" else max(0.0, previous.full_weight - step)
    return Representation(target, weight)


def _cheapest(held: str | None, prices: dict) -> str:
    """The name of the cheapest of `prices` (name -> ms; ties to the first), but the one `held` already
    while no other is cheaper by `SWITCH_MARGIN`: costs measured frame to frame wobble, and a choice
    near the break-even point would otherwise flicker, paying for a transition each time."""
    cheapest = min(prices, key=prices.get)
    if held in prices and prices[cheapest] >= (1.0 - SWITCH_MARGIN) * prices[held]:
        return held
    return cheapest
