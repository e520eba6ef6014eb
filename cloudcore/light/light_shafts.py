"""Light shafts: the sunlight the air would scatter toward the eye, taken away where the clouds shadow the air.

Yusov (HPG 2014, section 5.6) marches each view ray through a light-space cloud transparency buffer and integrates
the airlight only where the sun reaches the air; the sun streaming through gaps between clouds, and the dark
columns under them, are what is left.  Here the air's light between the eye and a surface is the
aerial-perspective volume's (`cloudcore.light.air_between`): A(t), the light the air adds over the first t metres
of a ray.  Its increase over a step, A(t_i+1) - A(t_i), is what that step's air adds as seen from the eye (its own
in-scattering already dimmed by the air in front of it), so the share of it the clouds' shadow keeps from the
step's air is taken away:

    shadowed = sum_i (1 - V(x_i)) (A(t_i+1) - A(t_i)),

V the clouds' transmittance map (`cloudcore.light.cloud_shadows`) at a point x_i within step i.  The steps span
only the part of the ray the map covers (a prism along the sun over the clouds' footprint, behind its near
plane): elsewhere nothing shadows the air.  A(t) holds the air's light scattered many times as well as once, which
the shadow dims alike: the clouds also shade the sky that lights the air under them.

The world pass's GL side (`cloudcore.gl.light_shafts`) marches the same steps at a fraction of the screen's
resolution; the sky takes `shadowed` off its light, and the terrain scales its air's light by what `shadowed_share`
leaves (a share, which changes little between neighbouring rays that end at different distances, where the light
taken does).  This is its numpy twin.
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.aerial_perspective import MAX_DISTANCE_M
from cloudcore.light.air_between import AirBetween
from cloudcore.light.cloud_shadows import LightSpace, sample_map

#: Rec. 709's luminance of linear RGB: the share taken is the luminance's
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])

#: steps along each ray's part in the map's prism: dithered across pixels and blurred over 3x3 (the GL march), 6
#: came within 0.2-1.4 dB of 12 on four views (docs/atmosphere.md#the-shafts-cheaper-issue-52s-budget)
SHAFT_STEPS = 6


def shaft_segments(space: LightSpace, eye, directions, distances) -> tuple[np.ndarray, np.ndarray]:
    """(start, end) (n,) metres: the part of each ray from `eye` along unit `directions` (n, 3) over its
    `distances` (n; at most `MAX_DISTANCE_M`, the air volume's reach) inside the map's prism: the map's texels
    across the sun, at or behind its near plane (slice coordinate 0) along it.  end <= start where a ray misses it."""
    directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    to_map = space.world_to_map()
    origin = to_map[:3, :3] @ np.asarray(eye, dtype=np.float64) + to_map[:3, 3]
    rates = directions @ to_map[:3, :3].T  # (n, 3): d(u, v, s)/dt
    start = np.zeros(len(directions))
    end = np.minimum(np.asarray(distances, dtype=np.float64).reshape(-1), MAX_DISTANCE_M)
    bounds = ((0, 0.0, 1.0), (1, 0.0, 1.0), (2, 0.0, np.inf))
    with np.errstate(divide="ignore", invalid="ignore"):  # a ray still along an axis takes neither face's
        for axis, low, high in bounds:
            rate, at = rates[:, axis], origin[axis]
            moving = np.abs(rate) > 1e-15
            to_low, to_high = (low - at) / rate, (high - at) / rate
            start = np.where(moving, np.maximum(start, np.fmin(to_low, to_high)), start)
            end = np.where(moving, np.minimum(end, np.fmax(to_low, to_high)), end if low <= at <= high else -1.0)
    return start, end


def shadowed_in_scattering(
    air: AirBetween,
    space: LightSpace,
    optical_depths: np.ndarray,
    eye,
    directions,
    distances,
    offsets=0.5,
    steps: int = SHAFT_STEPS,
) -> np.ndarray:
    """(n, 3): the air's light, in the renderer's values, that the clouds' shadow (the map `optical_depths` of
    `space`, `cloud_shadows.opacity_map`'s) keeps from the eye along each ray of `directions` (n, 3) from `eye` up
    to `distances` (n).  Each step's transmittance is read at `offsets` (n, or one value in [0, 1)) of its length:
    the GL side's dither across pixels."""
    directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    eye = np.asarray(eye, dtype=np.float64)
    start, end = shaft_segments(space, eye, directions, distances)
    length = np.maximum(end - start, 0.0)
    offsets = np.broadcast_to(np.asarray(offsets, dtype=np.float64), (len(directions),))

    shadowed = np.zeros((len(directions), 3))
    before = air.added(directions, start)[0]
    for step in range(steps):
        after = air.added(directions, start + length * (step + 1) / steps)[0]
        inside = start + length * (step + offsets) / steps
        points = eye + directions * inside[:, None]
        lit = np.exp(-sample_map(space, optical_depths, points))
        shadowed += (1.0 - lit)[:, None] * np.maximum(after - before, 0.0)
        before = after
    return np.where(length[:, None] > 0.0, shadowed, 0.0)


def shadowed_share(shadowed, whole) -> np.ndarray:
    """(...): the share of the air's light `whole` (..., 3) that the light `shadowed` (..., 3) taken from it is,
    by luminance, in [0, 1]."""
    taken, all_of_it = np.asarray(shadowed) @ LUMINANCE, np.asarray(whole) @ LUMINANCE
    return np.clip(taken / np.maximum(all_of_it, 1e-12), 0.0, 1.0)


#: how many times the cores of the points of the clouds' nearest depth cover a unit's disc, at most: a unit of
#: thousands of particles, each core a march pixel or less, draws about as many points as its disc has march
#: pixels, evenly through its order.  Every particle of the drawn units cost the 1.2M-particle field's frame a third
#: more, and the default scene's 90,000 (58,000 at 4 points a march pixel) the evening view's world pass a quarter
#: (docs/performance.md#the-light-shafts-cut-at-the-clouds)
NEAREST_DEPTH_COVERS = 1.0


def nearest_depth_particles(
    members, cloud_starts, centres, radii, particle_square_radii, core: float, eye, pixels_per_radian: float
) -> np.ndarray:
    """(n,) int32: the particles whose nearest depth ends the light shafts' march rays (Yusov's cut), of the units
    whose clouds are `members` (per unit its cloud indices into `cloud_starts`, a buffer's first particle of each
    cloud and its end), bounded by spheres at `centres` (units, 3) of `radii`, their particles' mean square radius
    `particle_square_radii` (units,), each drawn as the disc of `core` times its radius, seen from `eye` through a
    march of `pixels_per_radian`: every k-th particle of each of a unit's clouds, so that their discs (a march pixel
    at least) cover the unit's disc `NEAREST_DEPTH_COVERS` times; every particle of a unit that needs them all (a
    near one).  A ray a skipped particle would have cut ends farther, at the next core it crosses, or at the sky's."""
    starts = np.asarray(cloud_starts, dtype=np.int64)
    counts = np.array([len(unit) for unit in members], dtype=np.int64)
    kept = counts > 0
    if not kept.any():
        return np.zeros(0, dtype=np.int32)
    members, counts = [unit for unit in members if len(unit)], counts[kept]
    centres, radii = np.asarray(centres, dtype=np.float64)[kept], np.asarray(radii, dtype=np.float64)[kept]
    square_radii = np.asarray(particle_square_radii, dtype=np.float64)[kept]
    clouds = np.concatenate([np.asarray(unit, dtype=np.int64) for unit in members])
    firsts, particles = starts[clouds], starts[clouds + 1] - starts[clouds]
    distance = np.linalg.norm(centres - np.asarray(eye, dtype=np.float64), axis=1)
    # the unit's disc and a particle's, in march pixels (the eye within the sphere: the whole view, at most)
    disc = pixels_per_radian * np.arctan2(radii, np.maximum(distance - radii, 0.0))
    particle_disc = pixels_per_radian * core * np.sqrt(square_radii) / np.maximum(distance, 1e-9)
    # a point covers its disc, or the one pixel it falls on at least
    budget = np.maximum(NEAREST_DEPTH_COVERS * np.pi * disc**2 / np.maximum(np.pi * particle_disc**2, 1.0), 1.0)
    unit_particles = np.add.reduceat(particles, np.cumsum(counts) - counts)
    stride = np.repeat(np.maximum(np.floor(unit_particles / budget), 1.0).astype(np.int64), counts)
    taken = -(-particles // stride)  # ceil: a cloud's first particle, then every stride-th
    total = int(taken.sum())
    ends = np.cumsum(taken)
    within = np.arange(total) - np.repeat(ends - taken, taken)
    return (np.repeat(firsts, taken) + np.repeat(stride, taken) * within).astype(np.int32)
