"""The cloud pass at a fraction of the screen's resolution: its size, the world depth it is tested against, and the
depth-aware upsampling that lays it over the full-resolution world (Yusov 2014, section 5.4).

The GL draws it (`cloudcore.gl.reduced_clouds`, shaders/block_depth.frag.glsl and cloud_upsample.frag.glsl); the
functions here are the numpy twins the tests hold the shaders to, in GL's row order (bottom row first).

Each texel of the reduced pass stands for a block of the screen's pixels, and the clouds drawn into it are tested
against one depth for the whole block: the nearest of the block's world depths.  Taken the nearest, a texel keeps
only the clouds in front of everything in its block, so a terrain ridge, an object or the horizon crossing the block
is never covered by a cloud that is behind it there (the farthest would spread a cloud behind an aircraft's wing over
the wing: a halo of cloud on the object).  What a block straddling a depth edge loses is the clouds between its
near and its far surface, which its far pixels should see: they take them from a neighbouring texel whose block
lies at their own depth.  So the upsampling weighs the four reduced texels around a pixel by their bilinear share
and by how close the depth each was tested against is to the pixel's own, relative: on a smooth surface it is
bilinear, across a depth step it takes only the texels on the pixel's side.  A texel tested against a depth behind
the pixel's may hold clouds behind the pixel's surface (a cloud lying on a ridge), and weighs within a tenth of the
tolerance of one tested in front (`BEHIND_TOLERANCE`, `DEPTH_TOLERANCE`); the pixel's own block is never behind it.
Where none of the four is near the pixel's depth (a far pixel in a block straddling the edge whose three other
texels lie on the near side too, or one squeezed between near surfaces), it takes whole the texel whose depth is
nearest its own among the nine around its own texel.
"""

from __future__ import annotations

import math

import numpy as np

#: the relative difference of distances at which a reduced texel's weight in a pixel falls to 1/e: a step of terrain
#: against the sky, or of an object against the terrain behind it, is a difference of 1 or more; a slope of terrain
#: across a quarter-resolution block near the horizon (4 rows of 0.125 degrees at 6 degrees below it) one of 0.09
DEPTH_TOLERANCE = 0.1
#: the same for a texel tested against a depth behind the pixel's: only the depth buffer's own steps (6 m at 10 km)
#: and a little more; the clouds it holds between the two surfaces would cover the pixel's
BEHIND_TOLERANCE = 0.01
#: below this sum of weights no texel is at the pixel's depth (the nearest of them, 3 tolerances away, weighs
#: e^-9 of its bilinear share): the one whose depth is nearest is taken whole
NO_MATCH_WEIGHT = 1e-6


def reduced_size(viewport, scale: float) -> tuple[int, int]:
    """(width, height) of the cloud pass for a `viewport` (width, height) at `scale` of its resolution per axis."""
    return tuple(max(1, math.ceil(side * scale)) for side in viewport)


def block_starts(texels: int, pixels: int) -> np.ndarray:
    """The first pixel of the block of each of `texels` reduced texels along an axis of `pixels`: ceil(i * pixels /
    texels), each block running to the next one's first (the last to the axis' end)."""
    return -((-np.arange(texels) * pixels) // texels)  # integer ceil


def block_nearest_depth(depth: np.ndarray, size) -> np.ndarray:
    """The nearest (smallest) window depth of each block of `depth` (height, width) that a texel of the reduced
    pass of `size` (width, height) covers: what the reduced pass tests its clouds against."""
    height, width = depth.shape
    columns = np.minimum.reduceat(depth, block_starts(size[0], width), axis=1)
    return np.minimum.reduceat(columns, block_starts(size[1], height), axis=0)


def window_distance(depth, near_m: float, far_m: float) -> np.ndarray:
    """The distance along the view axis (metres) of window depths in [0, 1] of
    `cloudcore.world.camera.projection_matrix` with `near_m` and `far_m`: the far plane's for the sky's 1."""
    depth = np.clip(np.asarray(depth, dtype=np.float64), 0.0, 1.0)
    return near_m * far_m / (far_m - depth * (far_m - near_m))


def upsample(
    clouds: np.ndarray,
    cloud_depth: np.ndarray,
    world_depth: np.ndarray,
    near_m: float,
    far_m: float,
    tolerance: float = DEPTH_TOLERANCE,
    behind_tolerance: float = BEHIND_TOLERANCE,
) -> np.ndarray:
    """The reduced pass's premultiplied `clouds` (h, w, 4), tested against `cloud_depth` (h, w), at every pixel of the
    screen's `world_depth` (H, W) (window depths): cloud_upsample.frag.glsl's weights, in float64."""
    height, width = world_depth.shape
    h, w = cloud_depth.shape
    z = window_distance(world_depth, near_m, far_m)
    texel_z = window_distance(cloud_depth, near_m, far_m)
    at_x = (np.arange(width) + 0.5) * w / width - 0.5
    at_y = (np.arange(height) + 0.5) * h / height - 0.5
    base_x, base_y = np.floor(at_x), np.floor(at_y)
    fx, fy = at_x - base_x, at_y - base_y
    total = np.zeros((height, width))
    summed = np.zeros((height, width, 4))
    for ox, oy in ((0, 0), (1, 0), (0, 1), (1, 1)):
        tx = np.clip(base_x.astype(np.int64) + ox, 0, w - 1)
        ty = np.clip(base_y.astype(np.int64) + oy, 0, h - 1)
        bilinear = (fy if oy else 1.0 - fy)[:, None] * (fx if ox else 1.0 - fx)[None, :]
        zt = texel_z[ty[:, None], tx[None, :]]
        apart = np.abs(zt - z) / np.minimum(zt, z)
        weight = bilinear * np.exp(-((apart / np.where(zt > z, behind_tolerance, tolerance)) ** 2))
        summed += weight[..., None] * clouds[ty[:, None], tx[None, :]]
        total += weight
    # the pixel's own texel and the eight around it, for the one nearest in depth
    own_x, own_y = np.floor(at_x + 0.5).astype(np.int64), np.floor(at_y + 0.5).astype(np.int64)
    best = np.full((height, width), np.inf)
    nearest = np.zeros((height, width, 4))
    for oy in (-1, 0, 1):
        for ox in (-1, 0, 1):
            tx, ty = np.clip(own_x + ox, 0, w - 1), np.clip(own_y + oy, 0, h - 1)
            zt = texel_z[ty[:, None], tx[None, :]]
            apart = np.abs(zt - z) / np.minimum(zt, z)
            closer = apart < best
            best = np.where(closer, apart, best)
            nearest = np.where(closer[..., None], clouds[ty[:, None], tx[None, :]], nearest)
    matched = total > NO_MATCH_WEIGHT
    mean = summed / np.where(matched, total, 1.0)[..., None]
    return np.where(matched[..., None], mean, nearest)
