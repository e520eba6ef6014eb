"""Which splats a view keeps, and how much of the screen they cover (numpy).

A splat is a billboard of half side r, facing any way: it reaches `SPLAT_REACH` r from its centre, so a
frustum keeps the splats whose spheres of that radius touch it.  What they cover is the analytic overdraw
Harris and Wang reason with: the summed screen area of the splats over the screen area.  The estimate clips
each disc to the screen by its bounding square but ignores terrain in front, so it exceeds the measured mean
(`cloudcore.stats.overdraw`) where hills hide clouds.  The frame plan prices a unit near the eye by both
(`splats_in_view`).
"""

from __future__ import annotations

import math

import numpy as np

from cloudcore.maths.splat_kernel import SPLAT_REACH
from cloudcore.world.camera import points_in_eye_space, spheres_in_frustum


def splats_in_frustum(planes: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Boolean (N,): which splats (billboards of half side `radii`, facing any way) can touch the frustum.

    Next to the eye most of a cloud's particles are behind it or off to the side (along the default
    flythrough, 82% of those of the cloud the eye is in): they cost vertices and set-up for nothing.
    """
    return spheres_in_frustum(planes, centres, SPLAT_REACH * np.asarray(radii, dtype=np.float64))


def analytic_overdraw(
    centres: np.ndarray, radii: np.ndarray, view: np.ndarray, projection: np.ndarray, near: float
) -> float:
    """Sum of the splats' on-screen disc areas over the screen area (both in normalised device units).

    A splat is a disc of radius r parallel to the image plane at eye depth z, so
    its image is an ellipse of semi-axes r P[0,0] / z and r P[1,1] / z in NDC
    (x and y units differ by the aspect ratio); the screen is 2 x 2 NDC units.
    The part on screen is taken as the part of the disc's bounding box inside
    [-1, 1]^2.  Splats nearer than the near plane are not drawn.
    """
    eye_space = points_in_eye_space(centres, view)
    return _screen_share(eye_space, radii, np.flatnonzero(-eye_space[:, 2] > near), projection)


def splats_in_view(centres: np.ndarray, radii: np.ndarray, view: np.ndarray, projection: np.ndarray) -> tuple:
    """(how many splats the frustum of `view` and `projection` keeps, their `analytic_overdraw`).

    The splats kept are those `cloudcore.world.camera.splats_in_frustum` keeps, each a sphere of `SPLAT_REACH` times
    its radius against the frustum's six planes, here in eye space, where the planes of OpenGL's perspective
    projection are |P[i,i] x_i| <= depth (normals of length hypot(1, P[i,i])), depth >= near and depth <= far:
    one transform serves the cull and the areas (auto mode prices every near unit so, every frame: 0.29
    against 0.68 ms for four clouds' 10,655 splats culled in world space and transformed again, 0.17 against
    0.28 for one cloud's 4,796).
    """
    kept, overdraws = splats_in_view_per_set(centres, radii, [len(radii)], view, projection)
    return int(kept[0]), float(overdraws[0])


def splats_in_view_per_set(centres, radii, set_sizes, view, projection) -> tuple[np.ndarray, np.ndarray]:
    """`splats_in_view` of consecutive sets of splats at once, `set_sizes` of them each, in order: (per set, the
    splats kept, their `analytic_overdraw`).  The frame plan prices its near units so in one pass (a climb through
    small cumulus has several near the eye each frame; the default flythrough's units the eye is in and those
    near it, each frame: docs/performance.md, "The plan at Harris's scale")."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64)
    # eye space as three rows, each a product of the centres by a row of the view: no (N, 3) array is made (one of a
    # near cloud's splats is past the allocator's threshold, and faulted in afresh each time it is made)
    x, y, z = (np.add(centres @ view[axis, :3], view[axis, 3], out=np.empty(len(radii))) for axis in range(3))
    depth = np.negative(z, out=z)
    reach = SPLAT_REACH * radii
    scale, offset = projection[2, 2], projection[2, 3]
    near, far = offset / (scale - 1.0), offset / (scale + 1.0)
    kept = depth >= near - reach
    kept &= depth <= far + reach
    for axis, across in ((0, x), (1, y)):
        focal = projection[axis, axis]
        bound = math.hypot(1.0, focal) * reach
        bound += depth
        kept &= np.abs(focal * across) <= bound
    drawn = np.flatnonzero(kept & (depth > near))
    bounds = np.concatenate([[0], np.cumsum(set_sizes, dtype=np.int64)])
    areas = _run_sums(_screen_areas(x, y, depth, radii, drawn, projection), np.searchsorted(drawn, bounds))
    return _run_sums(kept, bounds), np.pi / 16.0 * areas


def _run_sums(values: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """The sums of `values` over the runs between consecutive `bounds` (indices, non-decreasing), an empty run's 0."""
    dtype = np.int64 if values.dtype == bool else np.float64
    # a run starting at the end reads the zero appended; reduceat gives an empty run its first value: zeroed
    sums = np.add.reduceat(np.append(values, np.zeros(1, dtype=values.dtype)), bounds[:-1], dtype=dtype)
    return np.where(bounds[1:] > bounds[:-1], sums, 0)


def _screen_share(eye_space: np.ndarray, radii: np.ndarray, drawn: np.ndarray, projection: np.ndarray) -> float:
    """`analytic_overdraw` of the splats at rows `drawn` (all in front of the near plane), given in eye space."""
    areas = _screen_areas(eye_space[:, 0], eye_space[:, 1], -eye_space[:, 2], radii, drawn, projection)
    return float(np.pi / 16.0 * np.sum(areas))


def _screen_areas(x, y, depth, radii: np.ndarray, drawn: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """Per splat at rows `drawn` (in front of the near plane; eye space's `x`, `y` and `depth`, -z), its disc's area
    on the screen in units of pi / 16 of the screen's."""
    inverse_depth = 1.0 / depth[drawn]
    drawn_radii = radii[drawn]
    # per axis the disc's bounding box on screen, 2 a wide, and the width w of its part in [-1, 1]; the
    # disc's area pi a_x a_y times the share w_x w_y / (4 a_x a_y) of its box on screen is pi w_x w_y / 4, over
    # the screen's 4: one array per axis, no division by a (the auto mode's planner runs this on every near
    # cloud's splats, every frame: the area and the share apart cost four times as much), clipped in place
    area = None
    for axis, across in ((0, x), (1, y)):
        scale = projection[axis, axis] * inverse_depth
        low, semi_axis = scale * across[drawn], scale * drawn_radii
        high = low + semi_axis
        low -= semi_axis
        width = np.minimum(np.maximum(high, -1.0, out=high), 1.0, out=high)
        width -= np.minimum(np.maximum(low, -1.0, out=low), 1.0, out=low)
        area = width if area is None else area * width
    return area
