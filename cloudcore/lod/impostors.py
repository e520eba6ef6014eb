"""Dynamic impostors (Schaufler; Harris section 3): their views, their error metrics, when to remake one.

An impostor of a cloud is the cloud rendered alone through a frustum fitted to
its bounding sphere from an eye, drawn afterwards as a quad through the
sphere's centre facing that eye.  It is good while the eye stays close to that
eye.  The *translation error* is, by default, Harris's own (SkyWorks,
`SkyRenderableInstanceCloud::IsImpostorValid`): the impostor stores the
nearest and farthest points of the bounding sphere along its view axis (here
those of its particles' discs, `content_depth`), and the error is the angle
between the rays from the current eye to those two points, the parallax that
a flat quad cannot show.  It is about 2R/D times
the angle the eye has turned around the centre, so a distant cloud tolerates
proportionally more motion (`parallax_error_deg`).  The stricter angle seen
from the centre is kept as the "centre" metric for comparison.  The
*resolution error* is a texture coarser than the cloud's current size on
screen asks for.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Hashable
from dataclasses import dataclass

import numpy as np

from cloudcore.model.scene import Camera
from cloudcore.world.camera import camera_pose, points_in_eye_space, pose_to_view, projection_matrix

#: an impostor texture at least this many times finer than needed is remade smaller (saves memory;
#: the factor keeps a cloud at a steady distance from flipping between two sizes)
SHRINK_FACTOR = 4
#: an eye closer to a cloud's centre than this many bounding radii counts as inside it; the margin keeps
#: the quad (half side R d / sqrt(d^2 - R^2)) within 3.2 R
INSIDE_RADII = 1.05


@dataclass(frozen=True)
class ImpostorRecord:
    """What an impostor texture was made from: the eye, the texture side, the lighting, the layers.

    A cloud split around objects (`cloudcore.lod.splitting`) has one texture per layer: `splits`
    are the distances from `eye` of the objects `split_objects` (far to near) when it was made.
    """

    eye: tuple[float, float, float]
    size: int
    lighting_key: Hashable
    splits: tuple[float, ...] = ()
    split_objects: tuple[int, ...] = ()
    #: the middle and half the depth, along the view axis from `eye`, of what the texture holds (its particles'
    #: discs; `content_depth`): the near and far points of Harris's parallax (None: the bounding sphere's)
    content: tuple[tuple[float, float, float], float] | None = None
    #: metres the wind had carried the unit when it was made, and the scene time then (`cloudcore.world.wind`): the
    #: quad follows the unit's drift since, and the error counts the eye's place relative to the moved unit and
    #: how far turbulence may have changed it
    drift: tuple[float, float, float] = (0.0, 0.0, 0.0)
    made_at_s: float = 0.0


@dataclass(frozen=True)
class ImpostorView:
    """The frustum that renders an impostor and the world-space quad that shows it."""

    view: np.ndarray
    projection: np.ndarray
    corners: np.ndarray  # (4, 3): lower left, lower right, upper left, upper right


def impostor_view(centre, radius: float, eye) -> ImpostorView:
    """The tight frustum around the sphere (centre, radius) from `eye`, which must lie outside it."""
    centre, eye = np.asarray(centre, dtype=np.float64), np.asarray(eye, dtype=np.float64)
    distance = float(np.linalg.norm(centre - eye))
    if not distance > radius:
        raise ValueError(f"an impostor needs the eye outside the cloud: distance {distance} <= radius {radius}")
    camera = Camera(tuple(eye), tuple(centre), math.degrees(2.0 * math.asin(radius / distance)))
    pose = camera_pose(camera)
    half_side = radius * distance / math.sqrt((distance - radius) * (distance + radius))
    right, up = pose[:3, 0] * half_side, pose[:3, 1] * half_side
    corners = np.array([centre - right - up, centre + right - up, centre - right + up, centre + right + up])
    near = max(distance - radius, distance * 1e-6)
    projection = projection_matrix(camera.fov_y_deg, 1.0, near=near, far=distance + radius)
    return ImpostorView(pose_to_view(pose), projection, corners)


#: texels of margin around the particles' extent (bilinear filtering reads one beyond the edge)
CROP_MARGIN_TEXELS = 2.0


def particle_extent(
    view: np.ndarray, projection: np.ndarray, centres: np.ndarray, radii: np.ndarray, size: tuple[int, int]
) -> tuple[float, float, float, float]:
    """(u0, v0, u1, v1) in [0, 1]: the part of a texture rendered through (view, projection) that the
    splats at `centres` (n, 3) with `radii` can cover, plus `CROP_MARGIN_TEXELS`.

    Cumulus are flatter than their bounding spheres, so drawing only this part of an impostor
    quad leaves out fragments that would all be transparent.  The whole texture when a splat
    reaches behind the eye (its projection is unbounded).
    """
    if len(radii) == 0:
        return (0.0, 0.0, 0.0, 0.0)
    eye_space = points_in_eye_space(centres, view)
    depth = -eye_space[:, 2]
    if not np.all(depth - radii > 0.0):
        return (0.0, 0.0, 1.0, 1.0)
    # a sphere lies in its bounding box, whose projection along each axis runs from (x - r) over the box's
    # nearest depth (x - r < 0) or its farthest (x - r >= 0) to the same for x + r; axis by axis on contiguous
    # columns, the projection's scale applied to the extremes: numpy loops over a row of two slowly, and a
    # regeneration pays this for each of up to 10,000 splats (0.36 against 0.02 ms)
    nearest, farthest = depth - radii, depth + radii
    low, high = np.empty(2), np.empty(2)
    for axis in (0, 1):
        left, right = eye_space[:, axis] - radii, eye_space[:, axis] + radii
        low[axis] = (left / np.where(left < 0.0, nearest, farthest)).min()
        high[axis] = (right / np.where(right > 0.0, nearest, farthest)).max()
    scale = np.array([projection[0, 0], projection[1, 1]])
    margin = 2.0 * CROP_MARGIN_TEXELS / np.asarray(size, dtype=np.float64)
    lowest, highest = np.minimum(low * scale, high * scale), np.maximum(low * scale, high * scale)
    lower = np.clip(0.5 * (lowest + 1.0) - margin / 2, 0.0, 1.0)
    upper = np.clip(0.5 * (highest + 1.0) + margin / 2, 0.0, 1.0)
    return (float(lower[0]), float(lower[1]), float(upper[0]), float(upper[1]))


def cropped_corners(corners: np.ndarray, extent) -> np.ndarray:
    """The quad `corners` (..., 4, 3: lower left, lower right, upper left, upper right) cut to `extent`
    (..., 4: u0, v0, u1, v1): one quad, or many at once (a frame's impostors)."""
    corners, extent = np.asarray(corners, dtype=np.float64), np.asarray(extent, dtype=np.float64)
    origin = corners[..., 0:1, :]
    right, up = corners[..., 1:2, :] - origin, corners[..., 2:3, :] - origin
    u = extent[..., [0, 2, 0, 2], None]  # per corner: u0, u1, u0, u1
    v = extent[..., [1, 1, 3, 3], None]
    return origin + u * right + v * up


def _tangent(radius, distance):
    """Half side of the impostor quad of a sphere seen from `distance` (> radius), over that distance (scalars,
    or arrays element by element)."""
    # the smallest normal float (np.finfo's tiny) from sys: np.finfo builds an object per call
    return radius / np.sqrt(np.maximum((distance - radius) * (distance + radius), sys.float_info.min))


def quad_half_side(radius, distance):
    """Half side in metres of the impostor quad through the centre of a sphere seen from `distance` (> radius)."""
    return _tangent(radius, distance) * distance


def screen_size_px(radius, distance, viewport_height: int, fov_y_deg: float):
    """Side in pixels of the impostor quad of a sphere seen from `distance` (> radius)."""
    return viewport_height * _tangent(radius, distance) / math.tan(math.radians(fov_y_deg) / 2.0)


def detail_size_px(radius, distance, finest_radius, texels):
    """Texture side that gives a particle of `finest_radius` `texels` texels of radius on the quad (each a scalar
    or an array, element by element).

    A cloud of Gaussian splats holds no detail finer than its smallest splat, so a
    texture finer than this only resamples smooth curves (Nyquist: 3 texels per radius
    sample the kernel's spectrum down to 8-bit quantisation; docs/lod.md).  Inf when
    there is no limit (`texels` 0, or a zero `finest_radius`).
    """
    finest_radius = np.asarray(finest_radius, dtype=np.float64)
    limited = (texels > 0.0) & (finest_radius > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(limited, 2.0 * texels * quad_half_side(radius, distance) / finest_radius, math.inf)


#: texture sides come in this many geometric steps per doubling: rounding up to the next power of two
#: would fill up to 4 times the texels asked for (a regeneration's cost on a CPU rasteriser is its fill),
#: quarter octaves at most 1.41 times, while a steady distance still maps to one size
SIZE_STEPS_PER_OCTAVE = 4


def required_size(pixels, smallest: int, largest: int):
    """The smallest texture side >= `pixels` of the form `smallest` * 2^(k / SIZE_STEPS_PER_OCTAVE) (rounded
    up to a multiple of 4 texels), within [smallest, largest]: an int, or an int64 array for an array."""
    pixels = np.asarray(pixels, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = np.ceil(SIZE_STEPS_PER_OCTAVE * np.log2(np.minimum(pixels, 2.0**30) / smallest) - 1e-9)
        sides = np.minimum(4.0 * np.ceil(smallest * 2.0 ** (steps / SIZE_STEPS_PER_OCTAVE) / 4.0 - 1e-9), largest)
    sizes = np.where(pixels > smallest, sides, smallest).astype(np.int64)
    return int(sizes) if sizes.ndim == 0 else sizes


def _angles_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles between the rows of two (n, 3) arrays; atan2 of |a x b| and a.b stays accurate for tiny angles,
    where acos does not."""
    # the cross product by components: np.cross costs 50 us of overhead a call, and the planner asks for
    # angles of every unit's impostor each frame
    (ax, ay, az), (bx, by, bz) = np.asarray(a, dtype=np.float64).T, np.asarray(b, dtype=np.float64).T
    sines = np.sqrt((ay * bz - az * by) ** 2 + (az * bx - ax * bz) ** 2 + (ax * by - ay * bx) ** 2)
    return np.degrees(np.arctan2(sines, ax * bx + ay * by + az * bz))


def content_depth(centre, radius: float, eye, centres: np.ndarray, radii: np.ndarray) -> tuple[tuple, float]:
    """(the point on the axis from `eye` through the bounding sphere (`centre`, `radius`) halfway through
    the depth of the splats at `centres` with `radii`, half that depth): the near and far points of the
    parallax metric for what an impostor made from `eye` holds.

    Cumulus are flatter than their spheres: along the default flythrough their particles' depth is
    0.78 of the sphere's diameter, and the parallax a flat quad cannot show is that depth's, not the
    sphere's.  The sphere's own points when there are no splats.
    """
    centre, eye = np.asarray(centre, dtype=np.float64), np.asarray(eye, dtype=np.float64)
    distance = float(np.linalg.norm(centre - eye))
    if len(radii) == 0 or not distance > 0.0:
        return tuple(float(v) for v in centre), float(radius)
    axis = (centre - eye) / distance
    depths = (np.asarray(centres, dtype=np.float64) - eye) @ axis
    near = max(float(np.min(depths - radii)), distance - radius)
    far = min(float(np.max(depths + radii)), distance + radius)
    if not near < far:
        return tuple(float(v) for v in centre), float(radius)
    middle = eye + axis * (0.5 * (near + far))
    return tuple(float(v) for v in middle), 0.5 * (far - near)


def centre_angles_deg(centres, radii, eyes_then, eye_now) -> np.ndarray:
    """(n,) angles at each of `centres` between the directions to its eye then (one row each, or one eye
    for all) and `eye_now` (0 when either coincides with it); `radii` are unused, for the metrics' one
    signature."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    then = np.broadcast_to(np.asarray(eyes_then, dtype=np.float64), centres.shape)
    return _angles_deg(then - centres, np.asarray(eye_now, dtype=np.float64) - centres)


def parallax_errors_deg(centres, radii, eyes_then, eye_now) -> np.ndarray:
    """Harris's translation error of n impostors at once: the angle at `eye_now` between each sphere's
    near and far points as seen from its eye then (SkyWorks' `_vecNearPoint`, `_vecFarPoint`), exactly 0
    at that eye (rounding in the rays would not give it), as SkyWorks.

    Inf once the far point has come nearer than the near point (SkyWorks' "backwards impostor"):
    the eye has passed the cloud's side and the quad shows it from behind; inf too for an eye then
    inside its sphere, or a row of NaN (no impostor held).
    """
    # in closed form: with u the unit axis from the eye then, a = d - r and b = d + r the near and far points'
    # distances along it and t the step from the eye now to the eye then, the rays from the eye now are u a + t and
    # u b + t, whose cross product is 2r (t x u) and dot product d^2 - r^2 + 2d (u.t) + t.t; one eye then (3,) is
    # never broadcast to rows, so the planner's test of every cloud of a ring costs a few passes over its centres
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    then = np.asarray(eyes_then, dtype=np.float64)
    now = np.asarray(eye_now, dtype=np.float64)
    (ax, ay, az), (tx, ty, tz) = (centres - then).T, (then - now).T
    distances = np.sqrt(ax * ax + ay * ay + az * az)
    outside = distances > radii  # False for NaN
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = 1.0 / np.where(outside, distances, 1.0)
        along = (ax * tx + ay * ty + az * tz) * scale  # u.t
        across = np.sqrt((ay * tz - az * ty) ** 2 + (az * tx - ax * tz) ** 2 + (ax * ty - ay * tx) ** 2) * scale
        backwards = (radii > 0.0) & (along < -distances)  # the far point nearer than the near one
        angles = np.degrees(
            np.arctan2(
                2.0 * radii * across,
                (distances - radii) * (distances + radii) + 2.0 * distances * along + (tx * tx + ty * ty + tz * tz),
            )
        )
        errors = np.where(outside & ~backwards, angles, np.inf)
    return np.where(np.all(then == now, axis=-1), 0.0, errors)


def translation_error_deg(centre, eye_then, eye_now) -> float:
    """Angle at `centre` between the directions to the two eyes (0 when either coincides with it)."""
    return float(centre_angles_deg(centre, None, eye_then, eye_now)[0])


def parallax_error_deg(centre, radius: float, eye_then, eye_now) -> float:
    """`parallax_errors_deg` of one sphere."""
    return float(parallax_errors_deg(centre, radius, eye_then, eye_now)[0])


#: translation metrics by name (`RenderSettings.translation_metric`), vectorised: (centres (n, 3), radii (n,),
#: eyes then (n, 3) or (3,), eye now) -> (n,) degrees
TRANSLATION_METRICS = {"parallax": parallax_errors_deg, "centre": centre_angles_deg}


def tolerance_deg_for(settings, fov_y_deg: float, viewport_height: int) -> float:
    """The translation tolerance in degrees: `tolerance_px` pixels at the screen's centre when set,
    else `tolerance_deg`."""
    if settings.tolerance_px > 0.0:
        return settings.tolerance_px * pixel_angle_deg(fov_y_deg, viewport_height)
    return settings.tolerance_deg


def pixel_angle_deg(fov_y_deg: float, viewport_height: int) -> float:
    """Degrees one pixel spans at the screen's centre."""
    return math.degrees(2.0 * math.atan(math.tan(math.radians(fov_y_deg) / 2.0) / max(viewport_height, 1)))


#: the order in which a regeneration budget serves reasons; rank 0 is never postponed: there is
#: no texture to show, or its layers would cut through an object
_REASON_RANK = {"new": 0, "layers": 0, "lights": 1, "resolution": 2, "translation": 3}


def regeneration_priority(
    reason: str, translation_ratio: float, split: bool, screen_px: float = 0.0
) -> tuple[int, float, float]:
    """Sort key of a wanted regeneration, most urgent first; `translation_ratio` is the translation
    error over the tolerance, `screen_px` the impostor's size on screen, which orders the rest (after
    a relight from a still eye, the largest on screen are remade first).  A cloud split around
    objects is never postponed."""
    return (0 if split else _REASON_RANK[reason], -translation_ratio, -screen_px)


def budgeted_regenerations(wanted, budget: int) -> set:
    """The indices to regenerate now out of `wanted` (index, `regeneration_priority`).

    At most `budget` (0: no limit), yet every one of rank 0; most urgent first, so a
    postponed impostor rises in the queue (its error grows) until it is served.
    """
    if not budget:
        return {index for index, _ in wanted}
    ranked = sorted(wanted, key=lambda w: w[1])
    must = sum(1 for _, priority in ranked if priority[0] == 0)
    return {index for index, _ in ranked[: max(budget, must)]}


def regeneration_reason(
    record: ImpostorRecord | None,
    size: int,
    lighting_key: Hashable,
    tolerance_deg: float,
    translation_error: float,
    layers_changed: bool = False,
) -> str | None:
    """Why the impostor must be remade this frame ("new", "lights", "resolution", "translation",
    "layers"), or None.

    `layers_changed`: the objects inside the cloud would cut its layers otherwise than its textures
    are (`cloudcore.lod.splitting.layers_hold`).  `translation_error` is the held impostor's, in
    degrees, by the metric in force (`TRANSLATION_METRICS`).
    """
    if record is None:
        return "new"
    if record.lighting_key != lighting_key:
        return "lights"
    if record.size < size or record.size >= SHRINK_FACTOR * size:
        return "resolution"
    if translation_error > tolerance_deg:
        return "translation"
    if layers_changed:
        return "layers"
    return None
