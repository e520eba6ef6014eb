"""`plan_frame`: one frame's plan from the units, the camera, the settings and the state the frame before left
(the stages: `pricing`, `choice`, `schedule`, `draw_items`; see the package's own docstring)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Hashable

import numpy as np

from cloudcore.lod.costs import CostModel, Work
from cloudcore.lod.impostors import (
    INSIDE_RADII,
    ImpostorRecord,
    budgeted_regenerations,
    content_depth,
    regeneration_priority,
    regeneration_reason,
)
from cloudcore.lod.plan.choice import (
    cheapest,
    cloud_pass_scale,
    comparable,
    groups_cheaper_apart,
    next_frame_choice,
    prices_units,
    represent_units,
    ring_outrun,
    ring_pays,
    ring_prices_hold,
    settled_in_full_3d,
    units_ms,
)
from cloudcore.lod.plan.draw_items import draw_items, full_runs, inside_runs
from cloudcore.lod.plan.frame_plan import FramePlan
from cloudcore.lod.plan.pricing import (
    AUTO_CLOUD_SCALE,
    NEAR_EXACT_RADII,
    Pricing,
    Seen,
    held_impostor_errors,
    in_view_work,
    ms_drawn_alone,
    panel_pixels,
    pricing_of,
    reduced_pass_work,
    representation_prices,
    ring_panels_work,
    ring_translation_error,
    ring_work,
    seen_from,
)
from cloudcore.lod.plan.schedule import within_frame_budget
from cloudcore.lod.plan.state import (
    LodState,
    Representation,
    RingPrices,
)
from cloudcore.lod.plan.unit_plans import (
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
    of_kinds,
)
from cloudcore.lod.ring import (
    RingCandidates,
    RingState,
    frames_to_show,
    plan_ring,
    ring_candidates,
    segment_texture_size,
    segments_of,
)
from cloudcore.lod.splat_coverage import splats_in_view_per_set
from cloudcore.lod.splitting import layers_hold, objects_reaching
from cloudcore.lod.units import LodUnits
from cloudcore.maths.depth_upsampling import reduced_size
from cloudcore.model.scene import Camera
from cloudcore.model.settings import AUTO_SCALE, RenderSettings
from cloudcore.world.camera import frustum_planes, projection_matrix, spheres_in_frustum, view_matrix
from cloudcore.world.wind import CloudMotion, shape_change_bound_m


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
    ring_keys: tuple | None = None,
    motion: CloudMotion | None = None,
) -> FramePlan:
    """Plan one frame of `units` (`cloudcore.lod.units.LodUnits`) seen by `camera`.

    `lighting_key` identifies what the particles' colours were computed from: one key for
    all clouds, or a tuple with one per cloud (the editor changes one cloud at a time, and
    only its unit's impostor is stale).  `objects` are the opaque objects' bounding spheres
    this frame (`cloudcore.world.objects.ObjectPose`); `cloud_particles(i)` gives cloud i's particle
    centres, asked only for units with objects inside.  `costs` prices auto mode's choices;
    by default the model `state.costs` has fitted to the frames so far.  `cloud_splats(i)` gives
    cloud i's (particle centres, radii), asked for units near the eye to count their fragments.
    `ring_keys`, per cloud, is what Wang's ring goes stale by where that is less than `lighting_key`: a cloud
    field's blend weights follow the eye's place, as parallax does, so the ring's rebuild distance bounds their
    change in its panels, while a key that changed with them rebuilt a field's ring every frame (None: the
    lighting keys).  `motion` (`cloudcore.world.wind.CloudMotion`) is what the wind has done to the clouds: an
    impostor follows its unit's drift, and its error counts the unit's motion and change since it was made
    (`held_impostor_errors`); None: still air.
    """
    scene_particles = float(np.sum(units.particle_counts))
    if state.frame_times and not comparable(state.particles, scene_particles):
        state = dataclasses.replace(state, frame_times={})  # another scene: what was measured says nothing of it
    if settings.mode == "auto" and settled_in_full_3d(state):
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
            ring_keys,
            motion,
        )
        drawn = {full_plan.clouds.members[i]: Representation("full", 1.0) for i in full_plan.clouds.indices_of("full")}
        return dataclasses.replace(
            full_plan,
            state=dataclasses.replace(
                full_plan.state,
                representations=drawn,
                frame_choice=next_frame_choice(state, "full", dict),  # the units are measured: no prediction is asked
                drawn_as="full",
                frames_drawn_as=state.frames_drawn_as + 1,
            ),
        )
    costs = state.costs.model() if costs is None else costs
    pricing = pricing_of(camera, viewport, settings, state, objects)
    groups_may_open = settings.mode == "auto" and settings.groups_apart_in_motion and units.clouds is not None
    # the units and, where groups may be planned apart, their clouds, priced in one pass: a pass costs about
    # 0.2 ms whatever its size (the field's groups priced apart 0.72 -> 0.15 ms a frame)
    priced_units = units.and_clouds if groups_may_open else units
    air_steps = (
        priced_units.member_means(motion.velocities) * (motion.time_s - state.time_s)
        if motion is not None and state.time_s is not None
        else None
    )
    seen = seen_from(
        priced_units, pricing, priced=prices_units(settings), air_steps=air_steps, turbulence=_turbulence(motion, state)
    )
    arguments = {
        "pricing": pricing,
        "seen": seen,
        "camera": camera,
        "viewport": viewport,
        "settings": settings,
        "state": state,
        "lighting_key": lighting_key,
        "objects": objects,
        "cloud_particles": cloud_particles,
        "costs": costs,
        "cloud_splats": cloud_splats,
        "ring_keys": ring_keys,
        "motion": motion,
    }
    if not groups_may_open:
        return _plan_units(units, frozenset(), **arguments)
    wanted = groups_cheaper_apart(units, seen, settings, state, costs, pricing.focal_px)
    held = wanted & state.opened
    plan = _plan_units(units, held, **arguments)
    # a group opens only where its own impostor is due anyway, so the switch steps no more than a regeneration
    due = frozenset(
        members
        for members in (plan.clouds.members[i] for i in {**plan.clouds.regenerate, **plan.clouds.postponed})
        if members in wanted - held
    )
    return _plan_units(units, held | due, **arguments) if due else plan


def _plan_units(
    units: LodUnits,
    opened: frozenset,
    pricing: Pricing,
    seen: Seen,
    camera: Camera,
    viewport: tuple[int, int],
    settings: RenderSettings,
    state: LodState,
    lighting_key: Hashable,
    objects,
    cloud_particles,
    costs: CostModel,
    cloud_splats,
    ring_keys: tuple | None,
    motion: CloudMotion | None,
) -> FramePlan:
    """`plan_frame` with the groups `opened` planned apart, their clouds each a unit of its own; `pricing` is
    `pricing_of`'s, `seen` the `seen_from` of the units (of `LodUnits.and_clouds` when groups may be opened)."""
    scene_particles = float(np.sum(units.particle_counts))
    if opened:
        rows = units.apart_rows(opened)
        units, seen = units.and_clouds.take(rows), seen.take(rows)
    else:
        seen = seen.take(slice(0, len(units.radii)))  # views: the units' own rows, first in `and_clouds`
    width, height = viewport
    priced = prices_units(settings)
    eye, last_eye, translation_error, tolerance = (
        pricing.eye,
        pricing.last_eye,
        pricing.translation_error,
        pricing.tolerance,
    )
    focal_px, screen_pixels = pricing.focal_px, pricing.screen_pixels
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
    unit_drifts = None if motion is None else units.member_means(motion.drifts)

    def unit_key(index: int) -> tuple:
        """What the colours of unit `index` were computed from: its clouds' keys."""
        return tuple(cloud_keys[c] for c in units.members[index])

    records = state.records
    objects_visible = spheres_in_frustum(planes, object_centres, object_radii)
    # auto mode prices Wang's ring against drawing its clouds each as auto would (the cheaper of full 3D and
    # an impostor): a sparse far field is cheaper drawn than its panels and their rebuilds
    ring_ms = alone_ms = 0.0
    candidates = np.zeros(len(radii), dtype=bool)
    # auto mode found the last frame cheaper drawn all in full 3D (`next_frame_choice`): every unit heads there
    all_full = settings.mode == "auto" and state.frame_choice == "full"
    # per unit, its full-3D work far off (particles, fragments): splat by splat for the ring's candidates in view
    in_view_particles, in_view_fragments = units.particle_counts.astype(np.float64), ball_fragments.copy()
    step = eye - last_eye if last_eye is not None else np.zeros(3)
    ring_prices, counted_in_view = None, False
    held_candidates: RingCandidates | None = None
    if settings.mode == "auto" and settings.uses_ring:
        held_candidates = ring_candidates(state.ring_candidates, units, eye, settings)
        candidates = held_candidates.members
        alone = candidates & visible
        ring_prices = state.ring_prices
        in_view_count = int(np.count_nonzero(alone))
        if ring_prices_hold(ring_prices, units, eye, view[2, :3], in_view_count, state, settings, costs):
            # the candidates' work in view as counted then: what the frame all in full 3D is predicted with
            (in_view_particles, in_view_fragments), counted_in_view = ring_prices.in_view_work, True
        else:
            segments = segments_of(centres[candidates], eye)
            seen_alone = visible[candidates]
            # the ring is kept within the tolerance, as every impostor is (rebuilt once its panels' error passes
            # it: `ring_translation_error`), and priced over the frames that lets it last
            ring_panels, ring_rebuild, lifetime = ring_work(
                units,
                candidates,
                segments,
                step,
                ball_fragments,
                panel_pixels(centres[alone], segments[seen_alone], quad_pixels_of[alone], view_projection, viewport),
                tolerance,
                eye,
                settings,
                state.ring,
            )
            if units.sample is not None:
                in_view_particles[alone], in_view_fragments[alone] = in_view_work(
                    units, alone, planes, eye, focal_px, screen_pixels, ball_fragments
                )
                counted_in_view = True
            in_view = (in_view_particles[alone], in_view_fragments[alone])
            ring_prices = RingPrices(
                eye=tuple(float(v) for v in eye),
                back=tuple(float(v) for v in view[2, :3]),
                frame_index=state.frame_index,
                generation=state.ring.pending or state.ring.current,
                costs=costs,
                units=units,
                in_view=in_view_count,
                in_view_work=(in_view_particles, in_view_fragments),
                ring_ms=costs.ms(ring_panels + ring_rebuild.scaled(1.0 / max(lifetime, 1.0))),
                alone_ms=ms_drawn_alone(units, seen, alone, in_view, focal_px, settings, costs),
            )
        ring_ms, alone_ms = ring_prices.ring_ms, ring_prices.alone_ms
        # a candidate drawn on its own until a ring being built takes it: an impostor made for it now lasts only
        # that long (Harris's circle at 800 clouds made 136 impostors in its first frame for a ring in 16 frames)
        lifetimes = np.where(candidates, np.minimum(lifetimes, frames_to_show(state.ring, step, settings)), lifetimes)
    ring_error = 0.0
    if settings.uses_ring and state.ring.current is not None:
        # under wind, the eye relative to the ring's clouds, as its panels follow them (`_ring_shift`)
        current = state.ring.current
        ring_eye = (
            eye - _ring_shift(current, current.rows_in(units.members, units.row_of), centres)
            if unit_drifts is not None
            else eye
        )
        ring_error = ring_translation_error(current, ring_eye)
    ring = plan_ring(
        state.ring,
        centres,
        radii,
        eye,
        settings,
        cloud_keys if ring_keys is None else ring_keys,
        units.members,
        units.member_set,
        segment_texture_size(height, camera.fov_y_deg, settings),
        holds_clouds=(
            not ring_outrun(state.ring, step, tolerance, settings)
            if settings.mode != "auto"
            else not all_full and ring_pays(state.ring, ring_ms, alone_ms)
        ),
        past_tolerance=ring_error > tolerance,
        # a segment is priced as its update is (below), by its particles: what the segment's render takes on
        # llvmpipe (478,000 particles of the 1.2M field, 368 ms: 0.77 us a particle, the fit's prior 0.85)
        build_ms=lambda members: costs.particles * float(units.particle_counts[units.row_of[members]]),
        step=step,
        heights=units.heights,
        # heading all to full 3D, the ring's clouds are drawn so at once, not faded out through impostors made for
        # the fade (the churning field: 67 made in the frame of the switch)
        at_once=all_full,
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

    def full_3d_of(indices: list) -> list:
        """Each unit of `indices` drawn in full 3D (`Work`): a ball of discs far off; near, splat by splat, only the
        splats in the frustum (the renderer leaves out the rest), their discs clipped to the screen, every near
        unit in one pass (`splats_in_view_per_set`); a still eye's again from last frame (auto mode's plan of the
        default view 4.65 -> 3.2 ms, best of 40)."""
        if not priced:
            return [Work() for _ in indices]
        works, counted = {}, []
        for index in indices:
            if cloud_splats is None or distances[index] >= NEAR_EXACT_RADII * radii[index]:
                particles, fragments = float(units.particle_counts[index]), float(ball_fragments[index])
                works[index] = Work(particles=particles, fragments=fragments)
                continue
            members = units.members[index]
            held = known_near.get(members)
            if held is not None and held[0] == unit_key(index):
                near_work[members], works[index] = held, held[1]
            else:
                counted.append(index)
        if counted:
            # the counted units' clouds' splats copied once, together (not a group's, then every unit's again), or
            # one cloud's as they are (a view of the particles): a copy of thousands faults in fresh memory
            clouds = [cloud_splats(cloud) for index in counted for cloud in units.members[index]]
            kept, overdraws = splats_in_view_per_set(
                clouds[0][0] if len(clouds) == 1 else np.concatenate([cloud_centres for cloud_centres, _ in clouds]),
                clouds[0][1] if len(clouds) == 1 else np.concatenate([cloud_radii for _, cloud_radii in clouds]),
                np.add.reduceat(
                    [len(cloud_radii) for _, cloud_radii in clouds],
                    np.cumsum([0] + [len(units.members[index]) for index in counted[:-1]]),
                ),
                view,
                projection,
            )
            for index, count, overdraw in zip(counted, kept.tolist(), overdraws.tolist()):
                fragments = float(screen_pixels * overdraw * units.fragment_costs[index])
                works[index] = Work(particles=float(count), fragments=fragments)
                near_work[units.members[index]] = (unit_key(index), works[index])
        return [works[index] for index in indices]

    representations = {}
    update_work, cloud_work = Work(), Work()
    # auto mode weighs the frame as planned unit by unit against every unit in full 3D in one sorted draw: splitting
    # the particles into many draws between impostors costs what no unit's own price shows
    individuals = 1.0 - (ring.weights(units.members, units.row_of) if ring is not None else np.zeros(len(radii)))
    in_ring = (individuals <= 0.0) & (radii > 0.0) & visible
    everything_full = Work(batches=1.0)  # and the units in the ring, counted only where asked (`predicted`)
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
    held_errors = (
        held_impostor_errors(units, drawable, records, translation_error, eye, motion, unit_drifts)
        if settings.mode != "full"
        else None
    )
    eye_in = distances[drawable] < INSIDE_RADII * radii[drawable]
    holders, outside = drawable[eye_in], drawable[~eye_in]  # the units the eye is in; those that may be impostors

    def decided(index: int, kind: int, inside: tuple, splits: tuple, full_weight=0.0, full_ms=0.0, impostor_ms=0.0):
        """Unit `index` drawn as `kind`, split around the objects `inside` it at `splits`."""
        kinds[index], full_weights[index] = kind, full_weight
        full_prices[index], impostor_prices[index] = full_ms, impostor_ms
        if splits:
            split_objects[index], split_distances[index] = inside, splits

    if settings.mode == "full":
        # every unit in view in full 3D, nothing priced: only the units holding objects are looked at one by one
        kinds[drawable], full_weights[drawable] = FULL, 1.0
        if priced:  # for the cloud pass's scale alone
            cloud_work = sum(full_3d_of(drawable.tolist()), cloud_work)
        for index in sorted(holding.intersection(drawable.tolist())):
            decided(index, FULL, *split_at(index, eye), full_weight=1.0)
        holders = outside = np.zeros(0, dtype=np.int64)
    # the eye inside: a screen impostor has fewer fragments than the screen, not fewer particles; its composite over
    # the screen is priced per run of inside units, below, and here, for the choice, as each unit's share of the
    # composites of the runs the units the eye is in would make, far to near (a sky flown through holds the eye in
    # tens of units, composited in a few runs: one composite each priced their particles always cheaper in full 3D)
    ordered = eye_in[np.argsort(-distances[drawable], kind="stable")]
    composites = np.count_nonzero(ordered & ~np.concatenate([[False], ordered[:-1]]))
    composite = Work(quad_pixels=screen_pixels, quads=1, batches=1).scaled(composites / max(len(holders), 1))
    # the units the eye is in drawn as screen impostors: their work so, and in full 3D (a reduced cloud pass no finer
    # than their screen impostor draws them into itself: `_cloud_pass`)
    inside_screen, inside_full = Work(), Work()
    # the units outside the eye near enough to be counted splat by splat
    near = (
        np.flatnonzero(distances[outside] < NEAR_EXACT_RADII * radii[outside])
        if cloud_splats is not None and settings.mode != "impostor"
        else np.zeros(0, dtype=np.int64)
    )
    # those and the units the eye is in counted in one pass: a pass has a fixed cost whatever its splats
    counted_one_by_one = holders.tolist() + outside[near].tolist()
    counted_works = dict(zip(counted_one_by_one, full_3d_of(counted_one_by_one)))
    for index in holders.tolist():
        full = counted_works[index]
        distance, members = float(distances[index]), units.members[index]
        individual = float(individuals[index])
        inside, splits = split_at(index, eye)
        everything_full += full
        screen_impostor = dataclasses.replace(full, fragments=full.fragments * settings.inside_resolution_scale**2)
        full_ms, inside_ms = (
            costs.ms(full),
            costs.ms(screen_impostor + composite),
        )
        if settings.mode == "auto" and individual == 1.0:
            previous = state.representations.get(members)
            held = previous.target if previous is not None and previous.full_weight == 1.0 else None
            # the same particles either way
            target = "full" if all_full else cheapest(held, {"full": full_ms, "inside": inside_ms})
            unit_prices.append((index, distance, full_ms, inside_ms))
            representations[members] = Representation(target, 1.0)
            if target == "full":
                decided(index, FULL, inside, splits, 1.0, full_ms, inside_ms)
                cloud_work += full
                continue
        decided(index, INSIDE, inside, splits, individual, full_ms, inside_ms)
        inside_screen += screen_impostor
        inside_full += full
    if len(outside):
        splits_of = {index: split_at(index, eye) for index in holding.intersection(outside.tolist())}
        layers = np.ones(len(outside))  # textures of an impostor: one more than the objects that cut it
        for index, (_, splits) in splits_of.items():
            layers[np.searchsorted(outside, index)] = len(splits) + 1
        # the units auto mode prices on their own: not fading into or out of the ring
        priced_each = settings.mode == "auto" and individuals[outside] == 1.0
        prices = representation_prices(
            units,
            outside,
            seen,
            lifetimes,
            layers,
            {row: counted_works[index] for row, index in zip(near.tolist(), outside[near].tolist())},
            priced_each,
            pricing,
            settings,
            costs,
            height,
            camera.fov_y_deg,
        )
        # a unit fading into or out of the ring is an impostor: one layer scales
        full_weight_of = np.zeros(len(outside))
        if settings.mode == "auto":
            full_weight_of, chosen, priced_units = represent_units(
                units.members,
                outside,
                distances[outside],
                priced_each,
                prices,
                state.representations,
                held_errors[outside],
                tolerance,
                all_full,
                settings,
            )
            representations.update(chosen)
            unit_prices += priced_units
        everything_full += Work(
            particles=float(np.sum(prices.full_particles)), fragments=float(np.sum(prices.full_fragments))
        )
        whole = full_weight_of == 1.0
        fading = (full_weight_of > 0.0) & ~whole
        shown = outside[~whole]  # as impostors, crossfading or not
        kinds[outside[whole]], full_weights[outside[whole]] = FULL, 1.0
        kinds[shown] = np.where(fading[~whole], CROSSFADE, IMPOSTOR)
        full_weights[shown] = (full_weight_of * individuals[outside])[~whole]
        impostor_weights[shown] = ((1.0 - full_weight_of) * individuals[outside])[~whole]
        texture_sizes[shown] = prices.textures.sizes[~whole]
        full_prices[outside], impostor_prices[outside] = prices.full_ms, prices.impostor_ms
        for index, (inside, splits) in splits_of.items():
            if splits:
                split_objects[index], split_distances[index] = inside, splits
        cloud_work += Work(
            particles=float(np.sum(prices.full_particles[whole | fading])),
            fragments=float(np.sum(prices.full_fragments[whole | fading])),
            # the impostors' quads, and a crossfade's screen layer
            quad_pixels=float(np.sum(prices.quad_pixels[~whole]) + screen_pixels * np.count_nonzero(fading)),
            quads=float(np.count_nonzero(~whole)),
        )
        # the impostors shown, each asked why it is remade: hundreds a frame where the ring is not kept (the climb)
        rows_shown = np.flatnonzero(~whole)
        for k, index, size, error in zip(
            rows_shown.tolist(),
            outside[rows_shown].tolist(),
            prices.textures.sizes[rows_shown].tolist(),
            held_errors[outside[rows_shown]].tolist(),
        ):
            record = records.get(units.members[index])
            reason = regeneration_reason(
                record,
                size,
                unit_key(index) if record is not None else None,  # none held: "new", whatever its key
                tolerance,
                error,
                # a unit no object reaches, and whose impostor had no layers, keeps them (most: no per-unit call)
                record is not None
                and (index in holding or bool(record.split_objects))
                and layers_changed(index, record),
            )
            if reason is not None:
                reasons[index] = reason
                ratio = error / max(tolerance, 1e-300)
                split = bool(splits_of.get(index, ((), ()))[1])
                priority = regeneration_priority(reason, ratio, split, float(prices.textures.pixels[k]))
                wanted.append((index, priority, prices.remake(k)))
    unit_prices.sort(key=lambda price: price[0])  # by index, as the units are numbered
    served = budgeted_regenerations([(index, priority) for index, priority, _ in wanted], settings.regeneration_budget)
    if settings.frame_budget_ms > 0.0:
        served &= within_frame_budget(wanted, settings.frame_budget_ms - costs.ms(cloud_work), costs)
    for index, _, remake in wanted:
        if index in served:
            update_work += remake
    # the largest translation error drawn, over the tolerance
    # (the ring shown while its rebuild is under way, past the tolerance as a postponed impostor is)
    accepted = 0.0 if ring is None or not ring.draws else ring_error / max(tolerance, 1e-300)
    regenerate, postponed = {}, {}
    textured = np.flatnonzero(of_kinds(kinds, *TEXTURED))
    # the impostors drawn as they were, not remade this frame: their errors
    is_served = np.zeros(count, dtype=bool)
    is_served[list(served)] = True
    kept = textured[~is_served[textured]]
    kept = kept[np.fromiter((units.members[i] in records for i in kept.tolist()), dtype=bool, count=len(kept))]
    if len(kept):  # (full mode holds no impostors, and measures no errors)
        accepted = max(accepted, float(np.max(held_errors[kept])) / max(tolerance, 1e-300))
    for index in textured.tolist():
        members = units.members[index]
        record = records.get(members)
        if index in served:
            record = next_records[members] = ImpostorRecord(
                tuple(float(v) for v in eye),
                int(texture_sizes[index]),
                unit_key(index),
                split_distances.get(index, ()),
                split_objects.get(index, ()),
                content_depth(centres[index], radii[index], eye, *splats_of(index)) if cloud_splats else None,
                (0.0, 0.0, 0.0) if unit_drifts is None else tuple(float(v) for v in unit_drifts[index]),
                0.0 if motion is None else motion.time_s,
            )
        reason = reasons.get(index)
        if reason is not None:
            (regenerate if index in served else postponed)[index] = reason
        texture_sizes[index] = record.size
    ring_shifts = []  # per generation drawn, how far the wind has carried its clouds since it was planned
    if ring is not None:
        for generation, _ in ring.draws:
            rows = generation.rows_in(units.members, units.row_of)
            ring_shifts.append(_ring_shift(generation, rows, centres) if unit_drifts is not None else np.zeros(3))
            shown = rows[visible[rows]]
            shown_segments = segments_of(centres[shown], generation.eye)
            pixels = panel_pixels(centres[shown], shown_segments, quad_pixels_of[shown], view_projection, viewport)
            cloud_work += ring_panels_work(len(generation.occupied_segments), pixels)
        builds = ring.segment_builds()
        update_work += Work(
            particles=float(sum(units.particle_counts[units.row_of[u]] for _, _, piece in builds for u in piece)),
            regenerations=float(sum(1 for _, _, piece in builds if piece)),
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
    drawn = np.flatnonzero(of_kinds(kinds, *DRAWN))
    draw_order = tuple(drawn[np.argsort(-distances[drawn], kind="stable")].tolist())
    inside_size = reduced_size(viewport, settings.inside_resolution_scale)
    items = draw_items(plans, draw_order, radii, object_centres, objects_visible, eye)
    cloud_scale, plans, items, cloud_work = _cloud_pass(
        plans,
        items,
        lambda unit_plans: draw_items(unit_plans, draw_order, radii, object_centres, objects_visible, eye),
        draw_order,
        cloud_work,
        inside_screen,
        inside_full,
        screen_pixels,
        settings,
        state.cloud_scale,
        costs if priced else None,
    )
    cloud_size = reduced_size(viewport, cloud_scale)
    between = set(items.objects)
    with_world = tuple(i for i in range(len(object_radii)) if objects_visible[i] and i not in between)
    drawn_as = frame_choice = None
    if settings.mode == "auto":
        drawn_as = "full" if all_full else "units"

        def predicted() -> dict:
            """The predicted ms of this frame's units each as priced and of every unit in full 3D: asked only while
            one of the two ways is not measured (the units in the ring counted splat by splat where their spheres
            leave the frustum, unless their ring was priced so this frame)."""
            if units.sample is not None and not counted_in_view:
                in_view_particles[in_ring], in_view_fragments[in_ring] = in_view_work(
                    units, in_ring, planes, eye, focal_px, screen_pixels, ball_fragments
                )
            ring_full = Work(
                particles=float(np.sum(in_view_particles[in_ring])), fragments=float(np.sum(in_view_fragments[in_ring]))
            )
            return {
                "units": units_ms(unit_prices, ring_ms, alone_ms, candidates, costs),
                "full": costs.ms(everything_full + ring_full),
            }

        frame_choice = next_frame_choice(state, drawn_as, predicted)
    next_state = LodState(
        records=next_records,
        ring=ring.state if ring is not None else RingState(),
        representations=representations,
        eye=tuple(float(v) for v in eye),
        costs=state.costs,
        cloud_scale=cloud_scale,
        frame_choice=frame_choice,
        drawn_as=drawn_as,
        frames_drawn_as=state.frames_drawn_as + 1 if state.drawn_as == drawn_as else 1,
        frame_index=state.frame_index + 1,
        frame_times=state.frame_times,
        particles=scene_particles,
        opened=opened,
        ring_prices=ring_prices,
        ring_candidates=held_candidates,
        object_centres=tuple(tuple(float(v) for v in centre) for centre in object_centres),
        near_work=(units, camera, tuple(viewport), near_work) if near_work else None,
        time_s=None if motion is None else motion.time_s,
    )
    return FramePlan(
        clouds=plans,
        draw_order=draw_order,
        ring=ring,
        state=next_state,
        inside_size=inside_size,
        cloud_size=cloud_size,
        cloud_scale=cloud_scale,
        draw_items=items,
        objects_with_world=with_world,
        update_work=update_work if priced else Work(),
        cloud_work=cloud_work if priced else Work(),
        priced=priced,
        costs=costs,
        tolerance_deg=tolerance,
        accepted_error=accepted,
        units=units,
        unit_drifts=unit_drifts,
        ring_shifts=tuple(ring_shifts),
        ring_build_shift=(
            _ring_shift(ring.building, ring.building.rows_in(units.members, units.row_of), centres)
            if unit_drifts is not None and ring is not None and ring.building is not None
            else np.zeros(3)
        ),
    )


def _cloud_pass(
    plans: UnitPlans,
    items,
    items_of,
    draw_order: tuple,
    drawn: Work,
    inside_screen: Work,
    inside_full: Work,
    screen_pixels: float,
    settings: RenderSettings,
    held_scale: float | None,
    costs: CostModel | None,
) -> tuple:
    """(scale, plans, draw items, work) of the cloud pass: at the screen's resolution, or at a fraction of it
    (`settings.cloud_resolution_scale`; "auto": the cheaper of the two by `costs`, None where the plan prices
    nothing, whose pass is the screen's).  `drawn` is the work of its draws but those of the units the eye is in,
    `inside_screen` and `inside_full` theirs as screen impostors and in full 3D; `items_of(plans)` makes the draw
    items of other plans, of the units `draw_order`.  A pass no finer than the screen impostor draws the units the
    eye is in into itself in full 3D: it is their screen impostor, laid over the screen once with the rest (Harris's
    quarter, Yusov's reduced pass)."""
    reduced_scale = settings.cloud_resolution_scale
    if reduced_scale == AUTO_SCALE:
        reduced_scale = AUTO_CLOUD_SCALE if costs is not None else 1.0

    def at(scale: float, unit_plans: UnitPlans, unit_items) -> Work:
        screen_impostors = len(inside_runs(unit_items, unit_plans))
        # the pass's own draws, their pixels the pass's; a screen impostor's splats are drawn at its own size
        work = (drawn if screen_impostors else drawn + inside_full) + Work(
            batches=float(full_runs(unit_plans.kinds[list(draw_order)]) + screen_impostors),
            quad_pixels=screen_impostors * screen_pixels,
            quads=float(screen_impostors),
        )
        if scale < 1.0:  # laid over the screen once, and once more after each object between cloud layers
            work = reduced_pass_work(work, scale, screen_pixels, 1 + len(unit_items.objects))
        return work + inside_screen if screen_impostors else work

    reduced_plans, reduced_items = plans, items
    if reduced_scale < 1.0 and reduced_scale <= settings.inside_resolution_scale and plans.count("inside"):
        reduced_plans = plans.inside_as_full()
        reduced_items = items_of(reduced_plans)
    if settings.cloud_resolution_scale == AUTO_SCALE and reduced_scale < 1.0:
        screen_work, reduced_work = at(1.0, plans, items), at(reduced_scale, reduced_plans, reduced_items)
        reduced_scale = cloud_pass_scale(held_scale, costs.ms(screen_work), costs.ms(reduced_work), reduced_scale)
    if reduced_scale == 1.0:
        return 1.0, plans, items, at(1.0, plans, items)
    return reduced_scale, reduced_plans, reduced_items, at(reduced_scale, reduced_plans, reduced_items)


def _turbulence(motion: CloudMotion | None, state: LodState) -> tuple[float, float] | None:
    """(metres turbulence may have moved a particle within its cloud since last frame, the most it may move one) under
    `motion`, for an impostor's lifetime (`seen_from`); None in still air, without turbulence or a last frame."""
    if motion is None or motion.wind is None or state.time_s is None:
        return None
    step = float(motion.shape_change_m([state.time_s])[0])
    return (step, shape_change_bound_m(motion.wind, math.inf)) if step > 0.0 else None


def _ring_shift(generation, rows: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(3,) metres the clouds of ring `generation` (its members' rows among the units now) have moved, on average,
    since it was planned: its panels move by it (the wind carries them all alike but for its bands); zeros where a
    member is gone (the ring is then made again)."""
    then = generation.spheres[0]
    if len(rows) != len(then) or not len(rows):
        return np.zeros(3)
    return centres[rows].mean(axis=0) - then.mean(axis=0)
