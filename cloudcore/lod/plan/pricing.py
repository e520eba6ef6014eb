"""What the plan prices units by, from this frame's eye: their distances, fragments, impostor quads and
lifetimes (`Seen`, for every unit at once), and the work of each representation: full 3D, an impostor, Wang's ring
and the clouds it would hold drawn on their own."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from cloudcore.lod.costs import CostModel, Work, regeneration_fragments, splat_fragments
from cloudcore.lod.impostors import (
    TRANSLATION_METRICS,
    detail_size_px,
    parallax_errors_deg,
    quad_half_side,
    required_size,
    screen_size_px,
    tolerance_deg_for,
)
from cloudcore.lod.plan.draw_items import full_runs
from cloudcore.lod.plan.state import LodState
from cloudcore.lod.plan.unit_plans import FULL, IMPOSTOR
from cloudcore.lod.ring import (
    SEGMENTS,
    RingState,
    panel_spans,
)
from cloudcore.lod.splat_coverage import splats_in_frustum
from cloudcore.lod.units import LodUnits
from cloudcore.maths.finite import nan_to_num
from cloudcore.maths.vectors import row_lengths
from cloudcore.model.scene import Camera
from cloudcore.world.camera import spheres_within_frustum

#: an impostor predicted to last longer than this many frames is priced as if it lasted this long
#: (a still eye would otherwise make any regeneration free)
LONGEST_LIFETIME_FRAMES = 120.0


#: bounding radii: a unit nearer than this has its full-3D fragments counted splat by splat, clipped to the
#: screen (`cloudcore.lod.splat_coverage.splats_in_view`); a ball of discs overestimates a near cloud tenfold, the
#: parts of it beside and behind the eye costing nothing
NEAR_EXACT_RADII = 3.0


@dataclass(frozen=True)
class Seen:
    """What the plan prices units by, per unit, from this frame's eye."""

    distances: np.ndarray  # of the centre from the eye
    ball_fragments: np.ndarray  # of full 3D, its splats a ball of discs (`splat_fragments`)
    half_sides: np.ndarray  # of the impostor quad through the centre, metres
    quad_pixels: np.ndarray  # of the impostor quad on the screen (all of it with the eye inside)
    #: frames an impostor made now lasts at the eye's speed (and an object's moving inside it), at most
    #: LONGEST_LIFETIME_FRAMES
    lifetimes: np.ndarray
    layers: np.ndarray  # textures of the impostor: one more than the objects inside

    def take(self, rows) -> Seen:
        """What is seen of the units at `rows`."""
        return Seen(*(getattr(self, field.name)[rows] for field in dataclasses.fields(self)))


def seen_from(units: LodUnits, pricing: Pricing, priced: bool = True, air_steps=None, turbulence=None) -> Seen:
    """What is seen of `units` from this frame's eye (`pricing`).  Not `priced` (full 3D), only the distances:
    every price zero.  `air_steps` (units, 3): how far the wind carried each unit since last frame (None: still
    air); relative to a unit, last frame's eye was that much further along, and its impostor lives as long as the
    eye's step relative to it allows.  `turbulence`: (metres a frame, metres at most) that turbulence may move a
    particle within its cloud (None: none), which `held_impostor_errors` adds to an impostor's error: it shortens
    the impostor's life as the parallax does (`_lifetimes`)."""
    eye, last_eye, focal_px, screen_pixels = pricing.eye, pricing.last_eye, pricing.focal_px, pricing.screen_pixels
    centres, radii = units.centres, units.radii
    distances = row_lengths(centres - eye)
    if not priced:
        nothing = np.zeros(len(radii))
        return Seen(distances, nothing, nothing, nothing, nothing, nothing + 1.0)
    # the translation error of one frame at the eye's current speed
    if last_eye is None:
        rates = np.zeros(len(radii))
    else:
        then = last_eye if air_steps is None else last_eye + air_steps
        rates = pricing.translation_error(centres, radii, then, eye)
    object_centres, object_radii, depth_steps = pricing.splitting
    if len(object_radii):
        reach = np.linalg.norm(centres[:, None] - object_centres[None], axis=2) < radii[:, None] + object_radii[None]
        reach &= (radii > 0.0)[:, None]
        split_lifetimes = _split_lifetimes(units, reach, object_radii, depth_steps)
        layers = 1.0 + np.count_nonzero(reach, axis=1)
    else:  # most scenes: no object splits a unit
        split_lifetimes, layers = np.full(len(radii), math.inf), np.ones(len(radii))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # the eye inside: the whole screen
        half_sides = radii * distances / np.sqrt(np.maximum((distances - radii) * (distances + radii), 1e-300))
        quad_pixels = nan_to_num(
            np.minimum((2.0 * focal_px * half_sides / distances) ** 2, screen_pixels), nan=screen_pixels
        )
    return Seen(
        distances,
        units.fragment_costs
        * splat_fragments(units.radius_squares, radii, distances, focal_px, units.particle_counts, screen_pixels),
        half_sides,
        quad_pixels,
        np.minimum.reduce(
            [
                _lifetimes(pricing.tolerance, rates, distances - radii, turbulence),
                split_lifetimes,
                np.full(len(radii), LONGEST_LIFETIME_FRAMES),
            ]
        ),
        layers,
    )


def _lifetimes(tolerance: float, rates, gaps, turbulence) -> np.ndarray:
    """Frames until an impostor made now passes `tolerance` degrees: its parallax grows by `rates` degrees a frame,
    and under `turbulence` (metres a frame, metres at most: `seen_from`) the change of its particles seen from the
    sphere's near side (`gaps` metres off) grows by at most that step's angle a frame, up to the angle of the most
    (`held_impostor_errors` adds the same).  Under a churning wind an impostor priced by its parallax alone was
    remade every few frames at a price that had it last until the eye moved."""
    if turbulence is None or turbulence[0] <= 0.0:
        return np.divide(tolerance, rates, out=np.full(len(rates), math.inf), where=rates > 0.0)
    step_m, most_m = turbulence
    near = np.maximum(gaps, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        shape_rates = np.degrees(np.divide(step_m, near, out=np.full(len(rates), math.inf), where=near > 0.0))
        most_deg = np.degrees(np.arctan2(most_m, near))
        # both growing (the angle of a step is at least what it adds to the angle: a bound) until the change
        # reaches its most; past that, the parallax alone has what the change left of the tolerance
        together = tolerance / (rates + shape_rates)
        parallax_after = np.divide(tolerance - most_deg, rates, out=np.full(len(rates), math.inf), where=rates > 0.0)
        return np.where(together <= most_deg / shape_rates, together, parallax_after)


def _split_lifetimes(units: LodUnits, reach, object_radii, depth_steps) -> np.ndarray:
    """Per unit, the frames until an object moving in depth inside it (`reach`: unit by object) remakes its
    layers: once it passes a particle it covers (`cloudcore.lod.splitting.layers_hold`), about every 2R / m
    metres of depth, m of the unit's particles overlapping it on screen, their share the area of a disc of its
    radius plus a typical particle's over the unit's."""
    radii = units.radii
    typical_radii = np.sqrt(units.radius_squares / np.maximum(units.particle_counts, 1.0))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        covered_shares = np.minimum(((object_radii[None] + typical_radii[:, None]) / radii[:, None]) ** 2, 1.0)
        spacings = 2.0 * radii[:, None] / np.maximum(units.particle_counts[:, None] * covered_shares, 1.0)
        split_lifetimes = nan_to_num(spacings / depth_steps[None], nan=math.inf)
    return np.min(np.where(reach, split_lifetimes, math.inf), axis=1, initial=math.inf)


class Pricing(NamedTuple):
    """What units are priced from this frame (`pricing_of`)."""

    eye: np.ndarray
    last_eye: np.ndarray | None  # last frame's, the speed that predicts an impostor's lifetime
    translation_error: object  # the translation metric (`cloudcore.lod.impostors.TRANSLATION_METRICS`)
    tolerance: float  # degrees
    focal_px: float  # the focal length in pixels
    screen_pixels: float
    #: (centres, radii, depth steps) of the objects that split units into layers (none unless `split_objects`),
    #: the steps how far each moved in depth since last frame
    splitting: tuple


def pricing_of(camera: Camera, viewport, settings, state: LodState, objects) -> Pricing:
    """What `seen_from` prices units from this frame."""
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
    return Pricing(
        eye=eye,
        last_eye=None if state.eye is None else np.asarray(state.eye, dtype=np.float64),
        translation_error=TRANSLATION_METRICS[settings.translation_metric],
        tolerance=tolerance_deg_for(settings, camera.fov_y_deg, height),
        focal_px=0.5 * height / math.tan(math.radians(camera.fov_y_deg) / 2.0),
        screen_pixels=float(width * height),
        splitting=splitting,
    )


class ImpostorTextures(NamedTuple):
    """Per unit of some rows (`impostor_textures`), its impostor's texture and what remaking it costs."""

    pixels: np.ndarray  # the quad's side on the screen
    sizes: np.ndarray  # the texture's side (int)
    fragments: np.ndarray  # of every particle splatted into the texture (`regeneration_fragments`)


def impostor_textures(units: LodUnits, rows, distances, height: int, fov_y_deg: float, settings) -> ImpostorTextures:
    """The impostor textures of the units at `rows` (indices) seen from `distances`: each as fine as the screen
    or the unit's detail asks, in `required_size`'s steps, and the fragments of remaking it."""
    radii, distance = units.radii[rows], distances[rows]
    pixels = screen_size_px(radii, distance, height, fov_y_deg)
    detail = detail_size_px(
        radii, distance, units.finest_radii[rows], settings.impostor_detail_texels * units.texel_scales[rows]
    )
    sizes = required_size(np.minimum(pixels, detail), settings.impostor_min_size, settings.impostor_max_size)
    half_sides = quad_half_side(radii, distance)
    fragments = units.fragment_costs[rows] * regeneration_fragments(
        units.particle_counts[rows], units.radius_squares[rows], radii, distance, half_sides, sizes
    )
    return ImpostorTextures(pixels, sizes, np.reshape(fragments, -1))


class RepresentationPrices(NamedTuple):
    """Per unit of some rows (`representation_prices`), the work and the price of it drawn in full 3D and as an
    impostor."""

    textures: ImpostorTextures
    layers: np.ndarray  # textures of its impostor: one more than the objects inside
    full_particles: np.ndarray  # full 3D's (none in impostor mode, which draws no such unit in full 3D)
    full_fragments: np.ndarray
    quad_pixels: np.ndarray  # of its impostor's quad on the screen
    remake_particles: np.ndarray  # of remaking its impostor, every layer
    remake_fragments: np.ndarray
    full_ms: np.ndarray
    impostor_ms: np.ndarray  # a frame, its remaking over its lifetime (inf: not priced)

    def remake(self, row: int) -> Work:
        """Remaking the impostor of the unit at `row` of these."""
        return Work(
            particles=float(self.remake_particles[row]),
            texture_fragments=float(self.remake_fragments[row]),
            regenerations=float(self.layers[row]),
        )


def representation_prices(
    units: LodUnits,
    rows,
    seen: Seen,
    lifetimes,
    layers,
    near_work: dict,
    priced,
    pricing: Pricing,
    settings,
    costs,
    height,
    fov_y_deg,
) -> RepresentationPrices:
    """What the units at `rows` (indices), seen from afar, cost in full 3D and as impostors: full 3D a ball of discs
    (`Seen.ball_fragments`), or `near_work` (row of these -> `Work`) for the near ones counted splat by splat; an
    impostor its quad and its remaking (one texture a layer, `layers`) over its lifetime (`lifetimes`, per unit: a ring
    candidate's impostor lasts until the ring takes it), where `priced` (a mask of these rows, or one for all: auto
    mode's units drawn on their own)."""
    count = len(rows)
    textures = impostor_textures(units, rows, seen.distances, height, fov_y_deg, settings)
    if settings.mode == "impostor":  # nothing drawn in full 3D but the units the eye is in: nothing else to price
        full_particles, full_fragments = np.zeros(count), np.zeros(count)
    else:
        full_particles = units.particle_counts[rows].astype(np.float64)
        full_fragments = np.asarray(seen.ball_fragments[rows], dtype=np.float64).copy()
        for row, work in near_work.items():
            full_particles[row], full_fragments[row] = work.particles, work.fragments
    quad_pixels = np.minimum(textures.pixels * textures.pixels, pricing.screen_pixels)
    remake_particles = units.particle_counts[rows] * layers
    remake_fragments = textures.fragments * layers
    remake_ms = (
        costs.particles * remake_particles + costs.texture_fragments * remake_fragments + costs.regenerations * layers
    )
    with np.errstate(invalid="ignore"):
        impostor_ms = np.where(
            priced,
            costs.quad_pixels * quad_pixels + costs.quads + remake_ms / np.maximum(lifetimes[rows], 1.0),
            math.inf,
        )
    return RepresentationPrices(
        textures,
        layers,
        full_particles,
        full_fragments,
        quad_pixels,
        remake_particles,
        remake_fragments,
        costs.particles * full_particles + costs.fragments * full_fragments,
        impostor_ms,
    )


def impostor_ms_of(units: LodUnits, seen: Seen, chosen, focal_px, settings, costs: CostModel) -> np.ndarray:
    """Per unit of `chosen` (a mask or indices), its impostor a frame: the quad, and the regeneration (every
    particle, into a texture as fine as the screen or the unit's detail asks) over the impostor's lifetime."""
    half_sides, distances, fragments = seen.half_sides[chosen], seen.distances[chosen], seen.ball_fragments[chosen]
    with np.errstate(divide="ignore", invalid="ignore"):
        sides = 2.0 * focal_px * half_sides / distances
        texels = settings.impostor_detail_texels * units.texel_scales[chosen]
        detail = 2.0 * texels * half_sides / units.finest_radii[chosen]
        detail = np.where(settings.impostor_detail_texels > 0.0, detail, np.inf)
        texture = np.clip(np.minimum(sides, detail), settings.impostor_min_size, settings.impostor_max_size)
        texture_fragments = fragments * nan_to_num((texture / sides) ** 2, nan=1.0)
    remake = seen.layers[chosen] * (
        costs.particles * units.particle_counts[chosen]
        + costs.texture_fragments * texture_fragments
        + costs.regenerations
    )
    return costs.quad_pixels * seen.quad_pixels[chosen] + costs.quads + remake / np.maximum(seen.lifetimes[chosen], 1.0)


def held_impostor_errors(
    units: LodUnits, drawable, records: Mapping, translation_error, eye, motion=None, unit_drifts=None
) -> np.ndarray:
    """Per unit, the translation error of the impostor held (inf: none), measured for the units `drawable` (the
    rest are not drawn on their own: out of view, or in the ring); the parallax between the near and far points
    of what it holds (`ImpostorRecord.content`) where the record has them.

    Under wind (`motion`, a `cloudcore.world.wind.CloudMotion`, and `unit_drifts` (units, 3) now) a unit's drift since
    its impostor was made is an eye's step the other way, measured as one; the most turbulence may have moved a
    particle within it since then, seen from the eye at the sphere's near side, is added in degrees."""
    rows = [row for row in drawable.tolist() if units.members[row] in records]
    errors = np.full(len(units.members), math.inf)
    if not rows:
        return errors
    held = [records[units.members[index]] for index in rows]
    centres, radii = units.centres[rows], units.radii[rows]
    eyes_now = np.asarray(eye, dtype=np.float64)
    if unit_drifts is not None:
        shifts = unit_drifts[rows] - np.array([record.drift for record in held], dtype=np.float64)
        eyes_now = eyes_now - shifts
        centres = centres - shifts
    if translation_error is parallax_errors_deg:  # what the impostors hold where their records have it (fresh rows)
        contents = [record.content for record in held if record.content is not None]
        if contents:
            holding = np.fromiter((record.content is not None for record in held), dtype=bool, count=len(held))
            centres[holding] = [centre for centre, _ in contents]
            radii[holding] = [radius for _, radius in contents]
    eyes = np.array([record.eye for record in held], dtype=np.float64)
    errors[rows] = nan_to_num(translation_error(centres, radii, eyes, eyes_now), nan=math.inf)
    if motion is not None:
        changed = motion.shape_change_m([record.made_at_s for record in held])
        gaps = np.linalg.norm(units.centres[rows] - np.asarray(eye, dtype=np.float64), axis=1) - units.radii[rows]
        errors[rows] += np.degrees(np.arctan2(changed, np.maximum(gaps, 0.0)))
    return errors


def in_view_work(units: LodUnits, chosen, planes, eye, focal_px, screen_pixels, ball_fragments):
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
    fragments += units.fragment_costs[indices] * np.bincount(owners, weights=weights * discs, minlength=count)
    return particles, fragments


def ms_drawn_alone(units: LodUnits, seen: Seen, chosen, in_view, focal_px, settings, costs) -> float:
    """The units `chosen` (mask) drawn each on its own as auto mode would, far from the eye: per unit the
    cheaper of full 3D (`in_view`: its particles and fragments in view) and an impostor (`impostor_ms_of`), and
    a splat draw for each run of them in full 3D between impostors, far to near (a sparse sky's small clouds
    drawn alone are many runs, each a draw of the cloud pass that the ring's panels do not make)."""
    full = costs.particles * in_view[0] + costs.fragments * in_view[1]
    impostor = impostor_ms_of(units, seen, chosen, focal_px, settings, costs)
    far_to_near = np.argsort(-seen.distances[chosen], kind="stable")
    kinds = np.where(full <= impostor, FULL, IMPOSTOR).astype(np.int8)[far_to_near]
    return float(np.sum(np.minimum(full, impostor))) + costs.batches * full_runs(kinds)


def panel_pixels(centres, segments, quad_pixels, view_projection: np.ndarray, viewport) -> float:
    """Pixels on the screen of the ring panels that show the clouds in view at `centres`, in the ring's
    `segments` (`segments_of`), whose own impostor quads would fill `quad_pixels`.

    A panel is cropped to the part its clouds cover and is one layer however many of them overlap: per
    segment, the box on the screen around its clouds' quads, within the screen, and at most their sum (a few
    clouds far apart fill less than their box).  Far clouds overlap on the horizon: their quads summed would
    price a scattered sky's panels at a screen or more where they fill a strip.
    """
    quad_pixels = np.asarray(quad_pixels, dtype=np.float64)
    if not len(quad_pixels):
        return 0.0
    width, height = viewport
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    clip = centres @ view_projection[:3, :3].T + view_projection[:3, 3]
    w = centres @ view_projection[3, :3] + view_projection[3, 3]
    half_sides = 0.5 * np.sqrt(quad_pixels)
    with np.errstate(divide="ignore", invalid="ignore"):
        x, y = (0.5 + 0.5 * clip[:, 0] / w) * width, (0.5 + 0.5 * clip[:, 1] / w) * height
    # segment by segment in one pass: the rows sorted by segment, each segment's extremes reduced at its start
    order = np.argsort(segments, kind="stable")
    starts = np.flatnonzero(np.concatenate([[True], np.diff(segments[order]) != 0]))
    x, y, half_sides, ahead = x[order], y[order], half_sides[order], (w > 0.0)[order]
    summed = np.add.reduceat(quad_pixels[order], starts)
    left = np.maximum(np.minimum.reduceat(x - half_sides, starts), 0.0)
    right = np.minimum(np.maximum.reduceat(x + half_sides, starts), float(width))
    bottom = np.maximum(np.minimum.reduceat(y - half_sides, starts), 0.0)
    top = np.minimum(np.maximum.reduceat(y + half_sides, starts), float(height))
    boxes = np.maximum(right - left, 0.0) * np.maximum(top - bottom, 0.0)
    # a cloud beside or behind the eye: its quad's box is unbounded, the screen at most
    boxes = np.where(np.logical_and.reduceat(ahead, starts), boxes, float(width * height))
    return float(np.sum(np.minimum(summed, boxes)))


def ring_panels_work(panels: int, pixels: float) -> Work:
    """Drawing `panels` ring panels (each a draw call) that fill `pixels` on the screen (`panel_pixels`)."""
    return Work(quad_pixels=float(pixels), quads=float(panels))


def ring_work(
    units: LodUnits,
    candidates,
    segments,
    step,
    ball_fragments,
    pixels,
    tolerance: float,
    eye,
    settings,
    state: RingState,
) -> tuple[Work, Work, float]:
    """(panels, rebuild, lifetime): Wang's ring holding the units `candidates` (mask), in `segments`, made at `eye`.

    Its panels drawn a frame (`pixels`: what they fill on the screen, `panel_pixels`), its rebuild (every
    candidate splatted into the segments, whose textures have the screen's pixel density), and the frames
    it lasts: until the eye's current `step` a frame carries it past a rebuild distance, or the frames the
    last ring lasted when shorter, or, shorter still, the frames until its panels' translation error could pass
    `tolerance` (degrees) at that step (the fastest rate of its `panel_spans`: the plan rebuilds it then).
    """
    panels = int(np.count_nonzero(np.bincount(segments, minlength=SEGMENTS)))
    horizontal, vertical, moving = math.hypot(step[0], step[2]), abs(step[1]), float(np.linalg.norm(step))
    centres, radii = panel_spans(units.centres[candidates], units.radii[candidates], eye, settings.ring_radius)
    distances = row_lengths(centres - np.asarray(eye, dtype=np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        rates = np.where(distances > radii, 2.0 * radii / ((distances - radii) * (distances + radii)), math.inf)
    lifetime = min(
        LONGEST_LIFETIME_FRAMES,
        state.rebuild_interval,
        settings.ring_rebuild_horizontal * settings.ring_radius / max(horizontal, 1e-300),
        settings.ring_rebuild_vertical * settings.ring_radius / max(vertical, 1e-300),
        # a parallax of s r' 2 / ((d' - r')(d' + r')) radians after a step s, at most (`ring_translation_error`)
        math.radians(tolerance) / max(float(np.max(rates, initial=0.0)) * moving, 1e-300),
    )
    rebuild = Work(
        particles=float(np.sum(units.particle_counts[candidates])),
        texture_fragments=float(np.sum(ball_fragments[candidates])),
        regenerations=float(panels),
    )
    return ring_panels_work(panels, pixels), rebuild, lifetime


#: the members of a ring whose parallax error is measured each frame; the rest are bounded (`ring_translation_error`)
RING_ERROR_WATCHED = 64


def ring_translation_error(generation, eye) -> float:
    """The largest translation error of a cloud of the ring `generation` (None: no ring; 0: none) seen from
    `eye`: Wang's panels are impostors too, pictures at the ring's radius of clouds that lie beyond it.

    Harris's parallax of each member's span from its panel to its own sphere's far side
    (`RingGeneration.panel_spans`), whatever the impostors' metric: the panel's shift against the cloud is
    itself a parallax.  Measured for the `RING_ERROR_WATCHED` spans whose error grows fastest with the eye's
    step from where the ring was made (`RingGeneration.fastest_parallax`), and for the rest only where their
    bound passes those: each parts its near and far rays by at most s 2r / ((d - r - s)(d + r - s)) radians
    after a step s shorter than d - r, so none of them passes s k (a / (a - s))^2, k the largest rate and a the
    nearest near point among them: a ring of thousands is measured whole only where that bound does not settle
    it.
    """
    if generation is None or not generation.members:
        return 0.0
    centres, radii = generation.panel_spans()
    then, now = np.asarray(generation.eye, dtype=np.float64), np.asarray(eye, dtype=np.float64)
    if len(radii) <= RING_ERROR_WATCHED:
        return float(np.max(parallax_errors_deg(centres, radii, then, now), initial=0.0))
    rows, rest_rate, rest_near = generation.fastest_parallax(RING_ERROR_WATCHED)
    largest = float(np.max(parallax_errors_deg(centres[rows], radii[rows], then, now)))
    step = float(np.linalg.norm(now - then))
    if rest_near > step and math.degrees(step * rest_rate * (rest_near / (rest_near - step)) ** 2) <= largest:
        return largest
    return float(np.max(parallax_errors_deg(centres, radii, then, now), initial=0.0))


#: the fraction of the screen's resolution per axis of the cloud pass when auto chooses a reduced one
#: (`cloud_resolution_scale = "auto"`): at a quarter, full 3D stayed within the level of detail's tolerance on the
#: three scenes measured (41-52 dB mean, 39-50 worst against the screen's resolution), and a half, whose pass has
#: the same fixed cost, saved less (docs/performance.md, "The cloud pass at a reduced resolution")
AUTO_CLOUD_SCALE = 0.25


def reduced_pass_work(drawn: Work, scale: float, screen_pixels: float, composites: int) -> Work:
    """The cloud pass whose draws are `drawn` at the screen's resolution drawn at `scale` of it per axis instead:
    the fragments and quad pixels its draws blend fall with its pixels, as scale^2; it adds its `composites` at full
    resolution (once, and once more after each object between cloud layers), a screen of upsampled pixels each with
    the wait before them (`Work.upsampled_pixels`)."""
    pixels_share = scale * scale
    return dataclasses.replace(
        drawn, fragments=drawn.fragments * pixels_share, quad_pixels=drawn.quad_pixels * pixels_share
    ) + Work(quads=float(composites), upsampled_pixels=composites * screen_pixels)
