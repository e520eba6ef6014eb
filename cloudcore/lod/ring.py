"""Wang's ring of impostors (section 6.2): far clouds on eight panels around the eye.

Clouds wholly beyond the ring radius (horizontally) and within the ring's
elevation band are rendered, from the eye at which the ring was made, into
eight textures of 45 degrees each; the panels form an octagon at the ring
radius.  The ring is remade when the eye has moved more than a fraction of
the radius (15% horizontally, 2% vertically, as in the paper) or, sooner, once
its panels' translation error passes the impostors' tolerance (a panel
stands at the radius, its clouds beyond it: `panel_spans`), the lights
changed, or the screen now asks for finer (or far coarser) segment textures
than the ring was made with (a window grown from its first, tiny frame): one
segment a frame, then the new ring crossfades in over a few frames while the
old one fades out.  Rebuilt, a segment dearer than the ring's share of a
frame (`RING_FRAME_MS`) is built in pieces over several frames, its clouds
far to near, each piece drawn over the last, while the last ring shows: the
1.2M-particle field's segments took 115 to 418 ms each, a stall in one
frame.  The first ring is built a segment a frame: until it is in, its
clouds are drawn on their own, at twice the field's frame.  Pure numpy; the GL
side renders what `RingPlan` says.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from cloudcore.lod.impostors import SHRINK_FACTOR, required_size
from cloudcore.model.scene import Camera
from cloudcore.model.settings import RenderSettings
from cloudcore.world.camera import camera_pose, frustum_planes, projection_matrix, spheres_in_frustum, view_matrix

SEGMENTS = 8
SEGMENT_DEG = 360.0 / SEGMENTS
#: the ring's share of a frame, ms by the cost model: what its build may take (`plan_ring`'s `build_ms`: a dearer
#: segment is built in pieces, a member at least each).  A third of a 30 fps frame on llvmpipe: the 1.2M-particle
#: field's segments, 115 to 418 ms each, then take 12 to 42 frames
RING_FRAME_MS = 10.0
#: metres: the panels never come nearer than this, so a zero ring radius still has a drawable octagon
MIN_PANEL_DISTANCE = 10.0


@dataclass(frozen=True, eq=False)
class RingGeneration:
    """One ring: where and for which lights it was made, which clouds it holds, per segment.

    Compared and hashed by identity: a generation is made once and carried from frame to frame (the GL side
    keys its segment textures by it)."""

    eye: tuple[float, float, float]
    radius: float
    #: the clouds of its members (the ids are tuples of cloud indices), and each one's lighting key when it was
    #: made (an object array): a member relit, formed or blended since makes it stale
    clouds: np.ndarray
    cloud_keys: np.ndarray
    members: frozenset  # the ids of the clouds (or units) it holds (`plan_ring`'s `ids`)
    segment_members: tuple  # SEGMENTS tuples of member ids, each far to near from `eye` (the order they are drawn)
    texture_size: tuple = (0, 0)  # (width, height) of its segment textures
    #: False: made while the ring did not pay for itself (`cloudcore.lod.plan`): it holds no cloud, and
    #: fading it in hands the last ring's clouds back to the frame plan
    holds_clouds: bool = True
    #: (centres (M, 3), radii (M,)) of the members' bounding spheres as the panels were rendered: what the plan
    #: measures the panels' translation error from each frame (`panel_spans`), without looking its members up
    #: among the units
    spheres: tuple = field(default=(np.zeros((0, 3)), np.zeros(0)), compare=False, repr=False)

    #: what the frames before found of it, so that a ring of thousands is not walked every frame: "rows", the
    #: tuple of ids last planned with and its members' rows in it; "unchanged", the clouds' lighting keys (the
    #: tuple a frame was planned with) and the set of ids last found to leave it as it was made; "spans", its
    #: `panel_spans`; "parallax", the spans whose parallax error grows fastest (`fastest_parallax`)
    _memo: dict = field(default_factory=dict, repr=False)

    @property
    def occupied_segments(self) -> tuple[int, ...]:
        """The segments holding a cloud: only they are rendered and drawn."""
        return tuple(segment for segment, clouds in enumerate(self.segment_members) if clouds)

    def panel_spans(self) -> tuple[np.ndarray, np.ndarray]:
        """(centres (M, 3), radii (M,)): per member, the sphere on its ray from `eye` whose near and far points are
        the nearest and farthest of its panel's point and its own sphere's near and far points (`panel_spans`),
        found once: what its translation error is measured on."""
        held = self._memo.get("spans")
        if held is None:
            held = self._memo["spans"] = panel_spans(*self.spheres, self.eye, self.radius)
        return held

    def fastest_parallax(self, count: int) -> tuple[np.ndarray, float, float]:
        """(the rows of `panel_spans` of the `count` whose parallax error grows fastest as the eye steps from
        `eye`, by the rate 2r / ((d - r)(d + r)) (inf: `eye` inside), the largest rate of the others, and their
        nearest near point d - r), found once."""
        held = self._memo.get("parallax")
        if held is None:
            centres, radii = self.panel_spans()
            distances = np.linalg.norm(centres - np.asarray(self.eye, dtype=np.float64), axis=1)
            near, far = distances - radii, distances + radii
            with np.errstate(divide="ignore", invalid="ignore"):
                rates = np.where(near > 0.0, 2.0 * radii / (near * far), math.inf)
            order = np.argpartition(-rates, count)
            others = order[count:]
            held = self._memo["parallax"] = (order[:count], float(np.max(rates[others])), float(np.min(near[others])))
        return held

    def rows_in(self, ids: tuple, row_of: Mapping) -> np.ndarray:
        """The rows of its members present in `ids` (whose `row_of` maps an id to its row), in the order of
        `members`."""
        held = self._memo.get("rows")
        if held is None or held[0] is not ids:
            held = self._memo["rows"] = (ids, np.array([row_of[m] for m in self.members if m in row_of], np.int64))
        return held[1]


@dataclass(frozen=True)
class RingState:
    """Carried from frame to frame: the ring shown, and the one being built or faded in."""

    current: RingGeneration | None = None
    pending: RingGeneration | None = None
    built: int = 0  # segments of `pending` built
    fade_step: int = 0
    #: frames since the last rebuild started, and between the last two starts (inf: fewer than two yet): how
    #: long a ring lasts, measured (a cloud field's cells leaving it rebuild it long before the eye's motion does)
    since_rebuild: int = 0
    rebuild_interval: float = math.inf
    built_of_segment: int = 0  # members of `pending`'s segment `built` drawn so far (a segment built in pieces)


@dataclass(frozen=True)
class RingPlan:
    """This frame's ring work: the segments to build (of `pending`), and the generations to draw with weights."""

    draws: tuple = field(default_factory=tuple)  # ((generation, weight), ...)
    state: RingState = RingState()
    #: ((segment, (start, stop)), ...): the members of `pending`'s segments drawn this frame, far to near; from 0 a
    #: segment's texture is cleared first, after it they are drawn over what is there.  One segment (or a piece of
    #: one) a frame, or several where the eye would outrun that (`rebuild_frames`)
    builds: tuple = ()
    #: the generation `builds` are of: `state.pending`, or `state.current` where it was finished and shown at once
    building: RingGeneration | None = None

    @property
    def build_segment(self) -> int | None:
        """The first segment built this frame (None: none)."""
        return self.builds[0][0] if self.builds else None

    @property
    def build_piece(self) -> tuple:
        """The members of `build_segment` drawn this frame, (start, stop)."""
        return self.builds[0][1] if self.builds else (0, 0)

    def segment_builds(self) -> tuple:
        """((segment, piece, the ids of the members drawn into it this frame), ...)."""
        if self.building is None:
            return ()
        members = self.building.segment_members
        return tuple((segment, piece, members[segment][slice(*piece)]) for segment, piece in self.builds)

    @property
    def build_members(self) -> tuple:
        """The ids of the members drawn into segments this frame (none: no segment built)."""
        return tuple(member for _, _, members in self.segment_builds() for member in members)

    def weights(self, ids: tuple, row_of: Mapping) -> np.ndarray:
        """The share of the opacity of each unit of `ids` (`RingGeneration.rows_in`) the ring shows this frame."""
        shown = np.zeros(len(ids))
        for generation, weight in self.draws:
            shown[generation.rows_in(ids, row_of)] += weight
        return shown


def segment_direction(segment: int) -> np.ndarray:
    """Horizontal unit vector through the middle of a segment; segment 0 starts at -z, turning toward +x."""
    azimuth = math.radians((segment + 0.5) * SEGMENT_DEG)
    return np.array([math.sin(azimuth), 0.0, -math.cos(azimuth)])


def segment_camera(generation: RingGeneration, segment: int, elevation_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """(view, projection) rendering one 45-degree segment of the ring from its eye."""
    eye = np.asarray(generation.eye, dtype=np.float64)
    camera = Camera(tuple(eye), tuple(eye + segment_direction(segment)), 2.0 * elevation_deg)
    aspect = math.tan(math.radians(SEGMENT_DEG / 2.0)) / math.tan(math.radians(elevation_deg))
    return view_matrix(camera), projection_matrix(camera.fov_y_deg, aspect)


def segments_of(centres, eye) -> np.ndarray:
    """The ring segment (0 to `SEGMENTS` - 1) each of `centres` lies in, by its azimuth about `eye`."""
    offsets = np.asarray(centres, dtype=np.float64).reshape(-1, 3) - np.asarray(eye, dtype=np.float64)
    azimuths = np.degrees(np.arctan2(offsets[:, 0], -offsets[:, 2])) % 360.0
    return (azimuths // SEGMENT_DEG).astype(np.int64) % SEGMENTS  # a tiny negative azimuth % 360 gives 360


def panel_spans(centres, radii, eye, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(centres (M, 3), radii (M,)): for each of the spheres `centres`, `radii` drawn on the panels of a ring of
    `radius` made at `eye`, the sphere on the ray from `eye` through its centre that spans the panel's point on
    that ray and the sphere's own near and far points along it.

    A panel is a flat picture at the ring's radius, not at its clouds' distance: seen from an eye moved s
    across from where it was made, a cloud at distance D shows s (1/R - 1/D) radians from where it is, 8.6 degrees
    for a cloud at infinity after Wang's 600 m at 4 km.  Harris's parallax of a span (the angle between the
    rays to its near and far points, `parallax_errors_deg`) bounds that shift and the cloud's own depth both; for
    an impostor, whose quad passes through its sphere, the span is the sphere itself (docs/lod.md, "Wang's
    ring")."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    offsets = centres - np.asarray(eye, dtype=np.float64)
    distances = np.linalg.norm(offsets, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        axes = offsets / distances[:, None]
        # the panel of the segment the centre lies in, a vertical plane `radius` off along the segment's middle:
        # the ray meets it at that distance over the cosine between the two
        azimuths = np.radians((segments_of(centres, eye) + 0.5) * SEGMENT_DEG)
        facing = axes[:, 0] * np.sin(azimuths) - axes[:, 2] * np.cos(azimuths)
        panel = max(radius, MIN_PANEL_DISTANCE) / facing
    near = np.minimum(panel, distances - radii)
    far = np.maximum(panel, distances + radii)
    return np.asarray(eye, dtype=np.float64) + axes * (0.5 * (near + far))[:, None], 0.5 * (far - near)


def panel_corners(generation: RingGeneration, segment: int, elevation_deg: float) -> np.ndarray:
    """(4, 3) world corners of a segment's panel (lower left, lower right, upper left, upper right)."""
    eye = np.asarray(generation.eye, dtype=np.float64)
    distance = max(generation.radius, MIN_PANEL_DISTANCE)
    pose = camera_pose(Camera(tuple(eye), tuple(eye + segment_direction(segment)), 60.0))
    right = pose[:3, 0] * distance * math.tan(math.radians(SEGMENT_DEG / 2.0))
    up = pose[:3, 1] * distance * math.tan(math.radians(elevation_deg))
    middle = eye + segment_direction(segment) * distance
    return np.array([middle - right - up, middle + right - up, middle - right + up, middle + right + up])


def ring_members(centres: np.ndarray, radii: np.ndarray, eye, settings: RenderSettings, heights=None) -> np.ndarray:
    """Boolean (N,): clouds wholly beyond the ring radius and wholly inside its elevation band, seen from `eye`.

    Inside the band by their spheres, or, where `heights` gives their splats' lowest and highest reach (N, 2), by
    those at the sphere's nearest horizontal distance: a cloud field's coarse cells are flat, their spheres
    kilometres high, and those that grazed the band's edge stayed out, drawn on their own over the panels that
    hold nearer clouds (docs/lod.md, "Wang's ring")."""
    tests = _RingTests.of(centres, radii, eye, settings, heights)
    return tests.beyond & tests.in_band


class _RingTests(NamedTuple):
    """`ring_members`' tests of each cloud from one eye, with the margins they pass or fail by."""

    beyond: np.ndarray  # wholly beyond the ring radius, horizontally
    beyond_margin: np.ndarray  # metres: its horizontal distance less its radius, less the ring radius
    horizontal: np.ndarray  # metres from the eye's vertical
    distance: np.ndarray  # metres from the eye
    cosine: np.ndarray  # of the elevation of the centre plus the sphere's angular radius
    sphere_in_band: np.ndarray
    #: per cloud, how far its splats' steepest reach (`heights`) lies within the band at the sphere's nearest
    #: horizontal distance, in metres of rise (None: no heights)
    heights_margin: np.ndarray | None

    @property
    def in_band(self) -> np.ndarray:
        if self.heights_margin is None:
            return self.sphere_in_band
        return self.sphere_in_band | (self.heights_margin >= 0.0)

    @staticmethod
    def of(centres, radii, eye, settings: RenderSettings, heights) -> _RingTests:
        x, y, z = (np.asarray(centres, dtype=np.float64) - np.asarray(eye, dtype=np.float64)).T
        horizontal_squared = x * x + z * z
        horizontal = np.sqrt(horizontal_squared)
        # the elevation of the centre plus the sphere's angular radius within the band, by their cosines (the
        # planner asks of every cloud each frame): cos(elevation + angular radius) = (h sqrt(d^2 - r^2) - |y| r) / d^2,
        # the sum at most 180 degrees, where the cosine falls
        distance_squared = horizontal_squared + y * y
        with np.errstate(invalid="ignore", divide="ignore"):
            cosine = (horizontal * np.sqrt(distance_squared - radii * radii) - np.abs(y) * radii) / distance_squared
        beyond_margin = horizontal - radii - settings.ring_radius
        beyond = (radii > 0) & (beyond_margin > 0.0)  # so wholly outside the eye's sphere too
        heights_margin = None
        if heights is not None:
            eye_y = float(np.asarray(eye, dtype=np.float64)[1])
            bottoms, tops = np.asarray(heights, dtype=np.float64).reshape(-1, 2).T
            # the steepest a splat can be seen at: its reach above or below the eye over the nearest horizontal
            # distance of the sphere (positive for a cloud beyond the radius)
            rise = np.maximum(tops - eye_y, eye_y - bottoms)
            with np.errstate(invalid="ignore"):
                heights_margin = math.tan(math.radians(settings.ring_elevation_deg)) * (horizontal - radii) - rise
        return _RingTests(
            beyond,
            beyond_margin,
            horizontal,
            np.sqrt(distance_squared),
            cosine,
            cosine >= math.cos(math.radians(settings.ring_elevation_deg)),
            heights_margin,
        )

    def slack(self, radii, settings: RenderSettings) -> np.ndarray:
        """Per cloud, metres the eye may move, any way, before its answer (`beyond & in_band`) may change.

        Beyond: the horizontal distance moves by at most the eye's step.  In the band by the sphere: the angle
        e + asin(r / d) (elevation e of the centre, d its distance) moves by at most pi s / (2 d) + s r / (a
        sqrt(a^2 - r^2)) after a step s at most (d - r) / 2, a = (d + r) / 2 (the ray to the centre turns by at
        most asin(s / d), and the angular radius grows fastest at the nearest distance); by the heights, the rise
        and the horizontal distance each by at most s.  An answer held by two tests holds while one of those
        that make it does."""
        band = math.radians(settings.ring_elevation_deg)
        radii = np.asarray(radii, dtype=np.float64)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            beyond_slack = np.where(radii > 0.0, np.abs(self.beyond_margin), math.inf)
            angle_margin = np.abs(band - np.arccos(np.clip(self.cosine, -1.0, 1.0)))
            nearest = 0.5 * (self.distance + radii)
            rate = 0.5 * math.pi / self.distance + radii / (nearest * np.sqrt(nearest * nearest - radii * radii))
            sphere_slack = np.minimum(angle_margin / rate, 0.5 * (self.distance - radii))
            if self.heights_margin is None:
                band_slack = sphere_slack
            else:
                heights_slack = np.abs(self.heights_margin) / (1.0 + math.tan(band))
                heights_in = self.heights_margin >= 0.0
                held_by = np.maximum(
                    np.where(self.sphere_in_band, sphere_slack, 0.0), np.where(heights_in, heights_slack, 0.0)
                )
                either = np.minimum(sphere_slack, heights_slack)
                band_slack = np.where(self.sphere_in_band | heights_in, held_by, either)
        in_band = self.in_band
        slack = np.where(
            self.beyond & in_band,
            np.minimum(beyond_slack, band_slack),
            np.maximum(np.where(self.beyond, 0.0, beyond_slack), np.where(in_band, 0.0, band_slack)),
        )
        return np.nan_to_num(slack, nan=0.0, posinf=math.inf)


#: `ring_candidates` asks `ring_members` again of every unit once more than this share of them may have changed
#: (their slack passed); fewer are asked alone
RING_CANDIDATES_REFRESH_SHARE = 0.125


@dataclass(frozen=True, eq=False)
class RingCandidates:
    """`ring_members` of a frame's units from an eye, held while the eye moves less than each answer's slack."""

    units: object  # the units asked of (by identity)
    radius: float
    elevation_deg: float
    eye: np.ndarray  # where every unit was last asked from
    slack: np.ndarray  # per unit, metres the eye may move from `eye` before its answer may change
    members: np.ndarray  # bool per unit: in the ring from this frame's eye


def ring_candidates(held: RingCandidates | None, units, eye, settings: RenderSettings) -> RingCandidates:
    """`ring_members` of `units` (`LodUnits`) from `eye`, the same answer, asking again only of the units whose
    answer may have changed since `held` (`_RingTests.slack`): auto mode asks of every unit each frame, and at
    Harris's scale (12,800 clouds) that was most of the time its plan spent on the ring while the ring's prices
    held (docs/lod.md, "Auto mode: the cheaper representation within the tolerance")."""
    eye = np.asarray(eye, dtype=np.float64)
    if (
        held is not None
        and held.units is units
        and held.radius == settings.ring_radius
        and held.elevation_deg == settings.ring_elevation_deg
    ):
        step = float(np.linalg.norm(eye - held.eye))
        # a margin for the rounding of the slacks themselves
        unsure = np.flatnonzero(held.slack <= 1.001 * step + 1e-9)
        if len(unsure) <= RING_CANDIDATES_REFRESH_SHARE * len(held.slack):
            members = held.members.copy()
            heights = None if units.heights is None else units.heights[unsure]
            members[unsure] = ring_members(units.centres[unsure], units.radii[unsure], eye, settings, heights)
            return replace(held, members=members)
    tests = _RingTests.of(units.centres, units.radii, eye, settings, units.heights)
    return RingCandidates(
        units,
        float(settings.ring_radius),
        float(settings.ring_elevation_deg),
        eye,
        tests.slack(units.radii, settings),
        tests.beyond & tests.in_band,
    )


def segment_texture_size(viewport_height: int, fov_y_deg: float, settings: RenderSettings) -> tuple[int, int]:
    """(width, height) of a ring segment texture: the screen's pixel density over 45 x 2 elevation degrees."""
    pixels_per_tangent = viewport_height / (2.0 * math.tan(math.radians(fov_y_deg) / 2.0))
    width = 2.0 * math.tan(math.radians(SEGMENT_DEG / 2.0)) * pixels_per_tangent
    height = 2.0 * math.tan(math.radians(settings.ring_elevation_deg)) * pixels_per_tangent
    return (
        required_size(width, settings.impostor_min_size, settings.impostor_max_size),
        required_size(height, settings.impostor_min_size, settings.impostor_max_size),
    )


def new_generation(
    centres,
    radii,
    eye,
    settings: RenderSettings,
    cloud_keys,
    ids: tuple,
    texture_size: tuple,
    holds_clouds=True,
    heights=None,
) -> RingGeneration:
    in_ring = ring_members(centres, radii, eye, settings, heights) & holds_clouds
    members = frozenset(ids[i] for i in np.flatnonzero(in_ring))
    clouds = np.array([cloud for member in members for cloud in member], dtype=np.int64)
    generation = RingGeneration(
        tuple(float(v) for v in eye),
        float(settings.ring_radius),
        clouds,
        np.fromiter(cloud_keys, dtype=object, count=len(cloud_keys))[clouds],
        members,
        (),
        tuple(texture_size),
        holds_clouds,
        (np.array(centres[in_ring], dtype=np.float64), np.array(radii[in_ring], dtype=np.float64)),
    )
    per_segment = []
    for segment in range(SEGMENTS):
        view, projection = segment_camera(generation, segment, settings.ring_elevation_deg)
        seen = np.flatnonzero(spheres_in_frustum(frustum_planes(projection @ view), centres, radii) & in_ring)
        far_to_near = seen[np.argsort(-np.linalg.norm(centres[seen] - np.asarray(eye), axis=1), kind="stable")]
        per_segment.append(tuple(ids[i] for i in far_to_near))
    return replace(generation, segment_members=tuple(per_segment))


def _relit(generation: RingGeneration, cloud_keys: tuple, present: frozenset) -> bool:
    """Whether the colours of a member of `generation` changed since it was made (`cloud_keys`: each cloud's
    lighting key now), or a member is gone (its cloud removed, or regrouped: not in `present`); a change to a
    cloud outside the ring leaves it be."""
    checked = generation._memo.get("unchanged")
    if checked is not None and checked[0] is cloud_keys and checked[1] is present:  # found unchanged before
        return False
    if not generation.members <= present:
        return True
    keys = np.fromiter(cloud_keys, dtype=object, count=len(cloud_keys))
    relit = bool(np.any(keys[generation.clouds] != generation.cloud_keys))
    if not relit:
        generation._memo["unchanged"] = (cloud_keys, present)
    return relit


def _wrong_size(generation: RingGeneration, texture_size: tuple) -> bool:
    """The screen asks for finer segment textures than the generation has, or for far coarser ones."""
    return any(
        held < wanted or held >= SHRINK_FACTOR * wanted for held, wanted in zip(generation.texture_size, texture_size)
    )


def _needs_rebuild(
    generation: RingGeneration,
    eye,
    settings: RenderSettings,
    cloud_keys: tuple,
    present: frozenset,
    texture_size: tuple,
    holds_clouds: bool,
    past_tolerance: bool,
) -> bool:
    if generation.holds_clouds != holds_clouds:
        return True
    if not holds_clouds:
        return False  # holding nothing, nothing goes stale
    return (
        past_tolerance
        or _relit(generation, cloud_keys, present)
        or _wrong_size(generation, texture_size)
        or generation.radius != settings.ring_radius
        or _moved_past(generation, eye, settings)
    )


def _moved_past(generation: RingGeneration, eye, settings: RenderSettings) -> bool:
    """The eye has moved past Wang's rebuild distance from the generation's eye, horizontally or vertically."""
    moved = np.asarray(eye, dtype=np.float64) - np.asarray(generation.eye)
    return (
        math.hypot(moved[0], moved[2]) > settings.ring_rebuild_horizontal * settings.ring_radius
        or abs(moved[1]) > settings.ring_rebuild_vertical * settings.ring_radius
    )


def plan_ring(
    state: RingState,
    centres,
    radii,
    eye,
    settings: RenderSettings,
    cloud_keys: tuple,
    ids: tuple,
    present: frozenset,
    texture_size: tuple,
    holds_clouds: bool = True,
    past_tolerance: bool = False,
    build_ms: Callable[[Hashable], float] | None = None,
    step=None,
    heights=None,
    at_once: bool = False,
) -> RingPlan | None:
    """Advance the ring by one frame: start a rebuild if needed, build one segment or step the fade.

    `cloud_keys` has each cloud's lighting key, `ids` one identity per sphere (a unit's
    member clouds), and `present` is the set of `ids`: the ring holds ids, so a scene whose spheres are
    renumbered (clouds regrouped, one removed) does not mistake one cloud for another.  `texture_size` is
    the segment texture size the screen asks for
    (`segment_texture_size`).  `holds_clouds` False asks for a ring of no clouds (it does not pay for
    itself): the ring shown fades out as when it is rebuilt, with nothing to build.  `past_tolerance`: the
    ring shown holds a cloud whose translation error, its panel's against it (`panel_spans`), has passed the
    impostors' tolerance: it is rebuilt as when the eye has moved past the rebuild distance.
    `build_ms`: per id, the predicted ms of drawing it into a segment; a ring rebuilt while one holding clouds
    shows draws a segment's members far to near in pieces of at most `RING_FRAME_MS` (one member at least), each
    over the last.  None, or no such ring shown: a segment a frame.  `step`: the eye's motion since the last
    frame (None: still), which sets the rebuild's pace (`rebuild_frames`): where a segment a frame and the fade
    would take longer than the eye takes to move a quarter of a rebuild distance, the segments are built several
    a frame, whole, and the fade is shortened, down to the whole ring built and shown in one frame.  `heights`:
    the spheres' splats' lowest and highest reach (`ring_members`; None: the spheres alone).  `at_once`: a ring of
    no clouds asked for (`holds_clouds` False) is shown in this frame, unfaded: auto mode heading all to full 3D
    draws the ring's clouds so at once, where a fade would draw each as an impostor made for it.

    A ring being built when its members' keys change is finished first and rebuilt after: a cloud
    forming in the ring, whose key changes every frame, would otherwise keep the ring from ever
    completing; one whose members are no longer all units (removed, regrouped), or whose eye the eye has
    moved past the rebuild distance from, starts again (at the eye's pace it is finished within half of it).
    """
    if not settings.uses_ring:
        return None
    current, pending, built, fade_step = state.current, state.pending, state.built, state.fade_step
    since_rebuild, rebuild_interval = state.since_rebuild + 1, state.rebuild_interval
    if pending is not None and (
        pending.radius != settings.ring_radius
        or _wrong_size(pending, texture_size)
        or not pending.members <= present  # a member gone (a cloud field's cell left): nothing to render it from
        or pending.holds_clouds != holds_clouds
        # the eye outran it (a jump): finished at the jump's pace it would show at once, from where the eye was,
        # the clouds that now fill its members' places (a cloud field's entering cells take the leaving ones')
        or (pending.holds_clouds and _moved_past(pending, eye, settings))
    ):
        pending = None  # the ring it was being built for is gone: start again
    if pending is None and (
        (current is None and holds_clouds)
        or (
            current is not None
            and _needs_rebuild(current, eye, settings, cloud_keys, present, texture_size, holds_clouds, past_tolerance)
        )
    ):
        newest = state.pending or current
        if newest is not None:
            # the frames a ring of clouds lasted, what its next rebuild is priced over (`pricing.ring_work`); a ring
            # dropped or taken up by auto mode's choice says nothing of it (dropped a frame after a rebuild began,
            # the climb's ring was priced at a rebuild a frame, 658 ms, and never taken up again)
            if newest.holds_clouds and holds_clouds:
                rebuild_interval = float(since_rebuild)
            since_rebuild = 0
        pending = new_generation(centres, radii, eye, settings, cloud_keys, ids, texture_size, holds_clouds, heights)
        built, fade_step = (0 if holds_clouds else SEGMENTS), 0  # a ring of nothing has nothing to build
    if at_once and pending is not None and not pending.holds_clouds:
        fade_step = settings.ring_fade_frames
    built_of_segment = state.built_of_segment if pending is state.pending else 0
    builds, building = (), pending
    pace = rebuild_pace(step, settings)
    if pending is not None:
        if built < SEGMENTS:
            if pace.in_pieces:
                members = pending.segment_members[built]
                shown = current is not None and current.holds_clouds  # else the clouds cost more until it is in
                stop = _piece_end(members, built_of_segment, build_ms if shown else None)
                builds = ((built, (built_of_segment, stop)),)
                built, built_of_segment = (built + 1, 0) if stop == len(members) else (built, stop)
            else:
                builds = tuple(
                    (segment, (built_of_segment if segment == built else 0, len(pending.segment_members[segment])))
                    for segment in range(built, min(built + pace.segments_a_frame, SEGMENTS))
                )
                built, built_of_segment = built + len(builds), 0
                if built == SEGMENTS and pace.fade_frames == 0:
                    fade_step = settings.ring_fade_frames  # no frame to fade in: shown this frame
        else:
            fade_step += pace.fade_steps_a_frame
    draws = ()
    if pending is not None and fade_step >= settings.ring_fade_frames:
        current, pending, built, fade_step = pending, None, 0, 0
    if pending is not None and fade_step > 0:
        weight = fade_step / settings.ring_fade_frames
        draws = ((pending, weight),) + (((current, 1.0 - weight),) if current is not None else ())
    elif current is not None:
        draws = ((current, 1.0),)
    return RingPlan(
        draws,
        RingState(current, pending, built, fade_step, since_rebuild, rebuild_interval, built_of_segment),
        builds,
        building if builds else None,
    )


#: a rebuild takes at most the frames the eye takes to move this share of a rebuild distance, so the ring shown is
#: never more than that past Wang's thresholds: at aircraft speeds his segment a frame and fade fit in it (the pace
#: is his wherever they do), and only an eye that would outrun them (a jump, a flight sampled sparsely) is built for
#: faster (docs/lod.md, "The ring's pace")
REBUILD_PACE_SHARE = 0.5


def rebuild_frames(step, settings: RenderSettings) -> float:
    """Frames the eye, moving `step` (x, y, z) a frame, takes to move `REBUILD_PACE_SHARE` of a rebuild distance,
    horizontally or vertically, whichever comes first (inf: a still eye)."""
    step = np.zeros(3) if step is None else np.asarray(step, dtype=np.float64)
    frames = math.inf
    for moved, share in (
        (math.hypot(step[0], step[2]), settings.ring_rebuild_horizontal),
        (abs(step[1]), settings.ring_rebuild_vertical),
    ):
        if moved > 0.0:
            frames = min(frames, REBUILD_PACE_SHARE * share * settings.ring_radius / moved)
    return frames


class RebuildPace(NamedTuple):
    """How fast a ring is rebuilt and faded in (`rebuild_pace`)."""

    segments_a_frame: int
    fade_frames: int  # frames the finished ring fades in over (0: shown the frame it is finished)
    fade_steps_a_frame: int  # of `RenderSettings.ring_fade_frames`
    #: Wang's pace: a segment a frame, or a piece of one where drawing it whole would take too long (`build_ms`)
    in_pieces: bool


def rebuild_pace(step, settings: RenderSettings) -> RebuildPace:
    """The rebuild's pace for an eye moving `step` a frame: at flying speeds a segment a frame and then the fade,
    as Wang; where the eye would move more than `REBUILD_PACE_SHARE` of a rebuild distance meanwhile, in as many
    frames as that leaves (none: the whole ring at once, shown at once).  Else the ring shown lags its eye by the
    rebuild's frames and, the rebuild distance passed again before it is in, never catches up (docs/lod.md, "The
    ring's pace")."""
    frames, fade = rebuild_frames(step, settings), settings.ring_fade_frames
    if frames >= SEGMENTS + fade:
        return RebuildPace(1, fade, 1, in_pieces=True)
    fade_frames = int(frames * fade / (SEGMENTS + fade))
    return RebuildPace(
        math.ceil(SEGMENTS / max(int(frames) - fade_frames, 1)),  # a share of the whole ring a frame
        fade_frames,
        math.ceil(fade / max(fade_frames, 1)),
        in_pieces=False,
    )


def frames_to_show(state: RingState, step, settings: RenderSettings) -> float:
    """Frames until the ring being built (or, with none yet, the first, begun this frame) shows its clouds
    whole at the eye's current `step` a frame: its segments left, then its fade (inf: no ring holding clouds is
    on its way)."""
    if state.current is None and state.pending is None:
        built, fade_step = 0, 0
    elif state.pending is None or not state.pending.holds_clouds:
        return math.inf
    else:
        built, fade_step = state.built, state.fade_step
    pace = rebuild_pace(step, settings)
    building = math.ceil((SEGMENTS - built) / pace.segments_a_frame)
    if pace.fade_frames == 0:
        return float(building)
    return float(building + math.ceil((settings.ring_fade_frames - fade_step) / pace.fade_steps_a_frame))


def _piece_end(members: tuple, start: int, build_ms: Callable[[Hashable], float] | None) -> int:
    """Where the piece of a segment's `members` drawn this frame from `start` ends: as many as fit in
    `RING_FRAME_MS` together, one at least."""
    if build_ms is None:
        return len(members)
    stop, spent = start, 0.0
    while stop < len(members):
        spent += build_ms(members[stop])
        if stop > start and spent > RING_FRAME_MS:
            break
        stop += 1
    return stop
