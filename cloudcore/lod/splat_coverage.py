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
    kept, overdraws = splats_in_view_by_owner(centres, radii, np.zeros(len(radii), dtype=np.int64), 1, view, projection)
    return int(kept[0]), float(overdraws[0])


def splats_in_view_by_owner(centres, radii, owners, count: int, view, projection) -> tuple[np.ndarray, np.ndarray]:
    """`splats_in_view` of `count` sets of splats at once, each splat's set its `owners` (0 to `count` - 1):
    (per set, the splats kept, their `analytic_overdraw`).  The frame plan prices its near units so in one pass
    (a climb through small cumulus has several near the eye each frame)."""
    eye_space = points_in_eye_space(centres, view)
    depth = -eye_space[:, 2]
    reach = SPLAT_REACH * np.asarray(radii, dtype=np.float64)
    scale, offset = projection[2, 2], projection[2, 3]
    near, far = offset / (scale - 1.0), offset / (scale + 1.0)
    kept = (depth >= near - reach) & (depth <= far + reach)
    for axis in (0, 1):
        focal = projection[axis, axis]
        kept &= np.abs(focal * eye_space[:, axis]) <= depth + math.hypot(1.0, focal) * reach
    drawn = np.flatnonzero(kept & (depth > near))
    owners = np.asarray(owners, dtype=np.int64)
    areas = np.bincount(owners[drawn], weights=_screen_areas(eye_space, radii, drawn, projection), minlength=count)
    return np.bincount(owners[kept], minlength=count), np.pi / 16.0 * areas


def _screen_share(eye_space: np.ndarray, radii: np.ndarray, drawn: np.ndarray, projection: np.ndarray) -> float:
    """`analytic_overdraw` of the splats at rows `drawn` (all in front of the near plane), given in eye space."""
    return float(np.pi / 16.0 * np.sum(_screen_areas(eye_space, radii, drawn, projection)))


def _screen_areas(eye_space: np.ndarray, radii: np.ndarray, drawn: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """Per splat at rows `drawn` (in front of the near plane, given in eye space), its disc's area on the screen
    in units of pi / 16 of the screen's."""
    inverse_depth = -1.0 / eye_space[drawn, 2]
    # per axis the disc's bounding box on screen, 2 a wide, and the width w of its part in [-1, 1]; the
    # disc's area pi a_x a_y times the share w_x w_y / (4 a_x a_y) of its box on screen is pi w_x w_y / 4, over
    # the screen's 4: one array per axis, no division by a (the auto mode's planner runs this on every near
    # cloud's splats, every frame: the area and the share apart cost four times as much)
    area = np.ones(len(inverse_depth))
    for axis in (0, 1):
        scale = projection[axis, axis] * inverse_depth
        centre, semi_axis = scale * eye_space[drawn, axis], scale * radii[drawn]
        area *= np.clip(centre + semi_axis, -1.0, 1.0) - np.clip(centre - semi_axis, -1.0, 1.0)
    return area
