"""The clouds' transmittance map in light space: how much of the sun's beam the clouds let through to any point.

An opacity shadow map (Kim and Neumann 2001; Yusov's light-space cloud transparency buffer, HPG 2014 section 5.6)
seen along the sun: an orthographic view over the clouds' footprint (whatever lies outside it is in no cloud's
shadow), `SLICES` depths across the clouds, and per texel and depth the optical depth of the particles in front
of it.  A particle of beam opacity b and radius r lets 1 - b K(rho / r) through at a distance rho from its axis
(`cloudcore.maths.splat_kernel`), so it adds the optical depth -ln(1 - b K) there: the transmittance through many is
exp(-sum), the product of theirs.

What a particle takes out of the beam differs by who receives it.  Another cloud's particles: the beam opacity
of Harris's light pass (`beam_opacity`): of the light a particle stops (its opacity alpha) it sends the share
sigma_eff / alpha on forward (`cloudcore.light.shading`), so the beam loses alpha - sigma_eff, as Yusov's
occlusion estimate takes it (`cloudcore.light.occlusion`'s xi); a cloud then shadows another as it shadows its own
particles (the default scene's particles, optical depth 8 at albedo 0.9, pass on 86% at their centres: by their
opacity alone the evening's clouds were each in another's).  The ground and the objects (the GL map,
`cloudcore.gl.shadow_map`): the opacity alpha itself, the direct sun blocked and the sky's light left, which the
path-traced truth's shadows on the ground bear out (`scripts/truth_shadows.py`, docs/atmosphere.md#cloud-shadows).
In depth a particle
is a slab of thickness 2 r: the share of it in front of a depth ramps from 0 to 1 across it.  Between the slices'
depths the optical depth is interpolated linearly, so a point behind every cloud (the ground) reads the whole
column and one in front of them reads 0.

A particle narrower than a texel is widened to one, its optical depth lowered to keep what it stops over the
plane (its integral): point sampled it would fall between texel centres or onto one, a shadow that flickers
as the sun moves.

Here the map is made in numpy (the GL side draws the same: `cloudcore.gl.shadow_map`, tested against this), and
the light reaching each cloud is dimmed by the other clouds' part of it (`between_clouds_transmittance`; a cloud's
own particles are Harris's light pass's: `cloudcore.light.illumination`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from cloudcore.light.phase import phase_function
from cloudcore.light.shading import scattering_coefficient
from cloudcore.maths.segments import concatenated_ranges
from cloudcore.maths.splat_kernel import splat_kernel

#: the depths the map holds the optical depth at: the GL map's two RGBA targets
SLICES = 8
#: texels across the longer side of the map the terrain and the objects read, and while a slider is dragged: chosen
#: by the ground's transmittance against a map of 2048 and the making's time (scripts/bench_shadows.py,
#: docs/atmosphere.md#cloud-shadows, "The resolution, by measurement"); a dragged slider's map is remade every look
#: and was the largest part of the frame that draws one, and its softer shadow edges cost the dragged picture less
#: than its coarse light pass does (docs/atmosphere.md#cloud-shadows, "A dragged slider's map at 128")
MAP_RESOLUTION, PREVIEW_MAP_RESOLUTION = 512, 128
#: texels across the map of a scene with a cloud field: made again nearly every frame of a flight (its clouds' blend
#: weights change), of particles hundreds of metres across (docs/atmosphere.md#cloud-shadows)
FIELD_MAP_RESOLUTION = 256
#: texels across the longer side of the map the light pass reads (clouds shadowing one another): the texel near
#: the default scene's particles' median radius; a coarser map was no faster, the particles' deposits costing it,
#: not the texels (docs/atmosphere.md#cloud-shadows)
BETWEEN_CLOUDS_RESOLUTION = 128
#: a particle's opacity times its kernel is capped at this, so that float32's 1 - b K stays above 0
MOST_OPACITY = 1.0 - 1e-6


def beam_opacity(optical_depth, albedo, phase: str = "rayleigh", g: float = 0.0) -> np.ndarray:
    """The share of the sun's beam a particle takes out of it at its centre: its opacity less what Harris's light
    pass sends on forward, alpha - sigma_eff (in [0, alpha])."""
    alpha = -np.expm1(-np.asarray(optical_depth, dtype=np.float64))
    forward = scattering_coefficient(optical_depth, albedo, phase, g) * float(phase_function(1.0, phase, g))
    return np.maximum(alpha - forward, 0.0)


@dataclass(frozen=True)
class LightSpace:
    """An orthographic view along the sun over a set of particles: texel coordinates across it, slice coordinates
    along it.

    `right`, `up` and `forward` are orthonormal (`forward` the light's travel, away from the sun); a point's
    (right, up) coordinates `origin` + (x, y) `texel_m` are texel x, y's corner, its forward coordinate
    `near_m` + s `slice_m` slice coordinate s: 0 in front of every particle, `SLICES` behind them all."""

    right: tuple[float, float, float]
    up: tuple[float, float, float]
    forward: tuple[float, float, float]
    origin: tuple[float, float]
    texel_m: float
    size: tuple[int, int]  # texels (across, up)
    near_m: float
    slice_m: float

    def texel_coordinates(self, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, s) of world `points` (n, 3): texel coordinates (texel i spans [i, i + 1)) and slice
        coordinate."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        x = (points @ np.asarray(self.right) - self.origin[0]) / self.texel_m
        y = (points @ np.asarray(self.up) - self.origin[1]) / self.texel_m
        s = (points @ np.asarray(self.forward) - self.near_m) / self.slice_m
        return x, y, s

    def moved(self, shift) -> LightSpace:
        """This view carried `shift` (3,) metres with what it was made over: the map of particles all moved by one
        translation (the wind's drift) is the same map, read at points less the shift."""
        shift = np.asarray(shift, dtype=np.float64)
        return dataclasses.replace(
            self,
            origin=(self.origin[0] + float(shift @ self.right), self.origin[1] + float(shift @ self.up)),
            near_m=self.near_m + float(shift @ self.forward),
        )

    def world_to_map(self) -> np.ndarray:
        """4x4: world (x, y, z, 1) to (u, v, s, 1), u and v texture coordinates in [0, 1] over the map, s the
        slice coordinate (what the GL side draws and reads the map by)."""
        width, height = self.size
        matrix = np.eye(4)
        matrix[0, :3] = np.asarray(self.right) / (self.texel_m * width)
        matrix[0, 3] = -self.origin[0] / (self.texel_m * width)
        matrix[1, :3] = np.asarray(self.up) / (self.texel_m * height)
        matrix[1, 3] = -self.origin[1] / (self.texel_m * height)
        matrix[2, :3] = np.asarray(self.forward) / self.slice_m
        matrix[2, 3] = -self.near_m / self.slice_m
        return matrix


def light_basis(sun_direction) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(right, up, forward): `forward` along the sun's light (-`sun_direction`), `up` the world's up as far as it
    is across the light (the world's z for a sun at the zenith or nadir)."""
    forward = -np.asarray(sun_direction, dtype=np.float64)
    forward = forward / np.linalg.norm(forward)
    hint = np.array([0.0, 1.0, 0.0]) if abs(forward[1]) < 0.99 else np.array([0.0, 0.0, 1.0])
    right = np.cross(forward, hint)
    right = right / np.linalg.norm(right)
    return right, np.cross(right, forward), forward


def light_space(centres, radii, sun_direction, resolution: int) -> LightSpace | None:
    """The view along `sun_direction` (toward the sun) over particles at `centres` (n, 3) of `radii` (n,), with
    `resolution` texels across the longer side of their footprint; None without particles."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64)
    if len(radii) == 0:
        return None
    right, up, forward = light_basis(sun_direction)
    across, along, depth = centres @ right, centres @ up, centres @ forward
    low = np.array([np.min(across - radii), np.min(along - radii)])
    high = np.array([np.max(across + radii), np.max(along + radii)])
    texel = float(np.max(high - low)) / resolution
    size = np.maximum(np.ceil((high - low) / texel).astype(int), 1)
    near, far = float(np.min(depth - radii)), float(np.max(depth + radii))
    return LightSpace(
        tuple(right),
        tuple(up),
        tuple(forward),
        (float(low[0]), float(low[1])),
        texel,
        (int(size[0]), int(size[1])),
        near,
        (far - near) / SLICES,
    )


def widened(radii, optical_depth_scale, texel_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(radii at least a texel, what scales each particle's optical depth so that its integral stays)."""
    radii = np.asarray(radii, dtype=np.float64)
    wide = np.maximum(radii, texel_m)
    return wide, optical_depth_scale * (radii / wide) ** 2


def slab_share(s, centre_s, half_thickness_s) -> np.ndarray:
    """The share of a particle's slab (centred at slice coordinate `centre_s`, `half_thickness_s` either side) in
    front of slice coordinate `s`."""
    return np.clip((s - centre_s + half_thickness_s) / (2.0 * half_thickness_s), 0.0, 1.0)


@dataclass(frozen=True)
class _Windows:
    """Rectangles of the map's texels, each with its own running sums over the slices (flat, one after another):
    the whole map, or each cloud's footprint."""

    corners: np.ndarray  # (w, 2) the lowest texel (x, y) of each
    sizes: np.ndarray  # (w, 2) texels (across, up)

    @property
    def offsets(self) -> np.ndarray:
        """Where each window's values start in the flat array, and the end."""
        return np.concatenate([[0], np.cumsum(np.prod(self.sizes, axis=1) * SLICES)])

    def index(self, window, x, y, k) -> np.ndarray:
        """The flat indices of texels (x, y) at slices k (1..SLICES) of `window`s (every texel in its window): a
        window holds (rows, columns, SLICES), so that all run over the slices in one cumsum."""
        local = (y - self.corners[window, 1]) * self.sizes[window, 0] + x - self.corners[window, 0]
        return self.offsets[window] + local * SLICES + k - 1

    def contains(self, window, x, y) -> np.ndarray:
        low, size = self.corners[window], self.sizes[window]
        return (x >= low[:, 0]) & (y >= low[:, 1]) & (x < low[:, 0] + size[:, 0]) & (y < low[:, 1] + size[:, 1])


def _boxes(space: LightSpace, centres, radii) -> tuple[np.ndarray, ...]:
    """Per particle (x, y, reach, x0, x1, y0, y1): its texel coordinates, its (widened) radius in texels and the
    texels [x0, x1) x [y0, y1) whose centres (i + 0.5) are in its disc's box, clipped to the map."""
    x, y, _ = space.texel_coordinates(centres)
    reach = widened(radii, 1.0, space.texel_m)[0] / space.texel_m
    width, height = space.size
    x0 = np.clip(np.ceil(x - reach - 0.5), 0, width).astype(np.int64)
    x1 = np.clip(np.floor(x + reach - 0.5) + 1, x0, width).astype(np.int64)
    y0 = np.clip(np.ceil(y - reach - 0.5), 0, height).astype(np.int64)
    y1 = np.clip(np.floor(y + reach - 0.5) + 1, y0, height).astype(np.int64)
    return x, y, reach, x0, x1, y0, y1


def _whole(space: LightSpace) -> _Windows:
    """The whole map as one window."""
    return _Windows(np.zeros((1, 2), np.int64), np.array([space.size], dtype=np.int64))


def _deposits(space: LightSpace, centres, radii, alpha) -> tuple[np.ndarray, ...]:
    """(particle, texel x, texel y, slice k in 1..SLICES, optical depth) for every texel whose centre lies in a
    particle's (widened) disc and every slice its slab steps into: the optical depth the particle adds there
    times the share of its slab between slice coordinates k - 1 and k (a particle's shares sum to 1, their
    running sum over k is `slab_share` at k)."""
    radii = np.asarray(radii, dtype=np.float64)
    x, y, reach, x0, x1, y0, y1 = _boxes(space, centres, radii)
    _, _, s = space.texel_coordinates(centres)
    scale = widened(radii, 1.0, space.texel_m)[1]
    columns = np.maximum(x1 - x0, 1)
    texels = (x1 - x0) * (y1 - y0)
    # the slices the slab steps into
    half = radii / space.slice_m
    first = np.clip(np.floor(s - half).astype(np.int64) + 1, 1, SLICES)
    last = np.clip(np.ceil(s + half).astype(np.int64), first, SLICES)
    steps = last - first + 1
    counts = texels * steps
    particle = np.repeat(np.arange(len(radii)), counts)
    pair = concatenated_ranges(np.zeros_like(counts), counts)
    texel, step = pair // steps[particle], pair % steps[particle]
    texel_x = x0[particle] + texel % columns[particle]
    texel_y = y0[particle] + texel // columns[particle]
    k = first[particle] + step
    distance = np.hypot(texel_x + 0.5 - x[particle], texel_y + 0.5 - y[particle]) / reach[particle]
    opacity = np.minimum(np.asarray(alpha, dtype=np.float64)[particle] * splat_kernel(distance), MOST_OPACITY)
    centre, thickness = s[particle], half[particle]
    # the last slice takes the rest: behind every slice, every particle counts whole
    behind = np.where(k == SLICES, 1.0, slab_share(k, centre, thickness))
    share = behind - slab_share(k - 1, centre, thickness)
    optical_depth = -np.log1p(-opacity) * scale[particle] * share
    keep = optical_depth > 0.0
    return particle[keep], texel_x[keep], texel_y[keep], k[keep], optical_depth[keep]


def _accumulate(windows: _Windows, window, x, y, k, optical_depth) -> np.ndarray:
    """The windows' values (flat): deposits summed per texel and slice, then run over the slices."""
    flat = np.bincount(windows.index(window, x, y, k), weights=optical_depth, minlength=int(windows.offsets[-1]))
    return np.cumsum(flat.reshape(-1, SLICES), axis=1).ravel()


def _sample(windows: _Windows, values: np.ndarray, window, x, y, s) -> np.ndarray:
    """The optical depth at texel coordinates (x, y) and slice coordinates s in `window`s: bilinear between
    texel centres (0 off the window, as the GL map is off the map), linear between slices (0 at slice
    coordinate 0 and in front, the last slice's behind)."""
    s = np.clip(s, 0.0, SLICES)
    below = np.minimum(np.floor(s).astype(np.int64), SLICES - 1)
    along = s - below
    fx, fy = x - 0.5, y - 0.5
    ix, iy = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
    wx, wy = fx - ix, fy - iy
    total = np.zeros(len(s))
    for dx, dy, weight in ((0, 0, (1 - wx) * (1 - wy)), (1, 0, wx * (1 - wy)), (0, 1, (1 - wx) * wy), (1, 1, wx * wy)):
        tx, ty = ix + dx, iy + dy
        inside = windows.contains(window, tx, ty)
        for k, share in ((below, 1.0 - along), (below + 1, along)):
            index = windows.index(window, tx, ty, np.maximum(k, 1))
            value = np.where(inside & (k >= 1), values[np.where(inside, index, 0)], 0.0)
            total += weight * share * value
    return total


def opacity_map(space: LightSpace, centres, radii, alpha) -> np.ndarray:
    """(SLICES, height, width): the optical depth in front of slice coordinates 1..SLICES at each texel's centre,
    of particles at `centres` (n, 3) of `radii` (n,) and beam opacity `alpha` (n,); slice coordinate 0 holds none."""
    width, height = space.size
    _, x, y, k, optical_depth = _deposits(space, centres, radii, alpha)
    values = _accumulate(_whole(space), np.zeros(len(x), np.int64), x, y, k, optical_depth)
    return np.moveaxis(values.reshape(height, width, SLICES), 2, 0)


def sample_map(space: LightSpace, values: np.ndarray, points) -> np.ndarray:
    """The optical depth `opacity_map` `values` hold at world `points` (n, 3), read as the GL side reads it."""
    x, y, s = space.texel_coordinates(points)
    flat = np.moveaxis(np.asarray(values, dtype=np.float64), 0, 2).ravel()
    return _sample(_whole(space), flat, np.zeros(len(x), np.int64), x, y, s)


def between_clouds_transmittance(
    centres, radii, alpha, cloud_starts, sun_direction, resolution: int = BETWEEN_CLOUDS_RESOLUTION
) -> np.ndarray:
    """(n,): the share of the sun's beam (toward `sun_direction`) that the other clouds let reach each particle of
    clouds whose particles (`centres` (n, 3), `radii`, beam opacity `alpha`) are concatenated at `cloud_starts`.

    The map of every cloud less, on the same texels, the map of the particle's own cloud: the two are summed
    from the same deposits, so a lone cloud's particles get exactly 1."""
    radii = np.asarray(radii, dtype=np.float64)
    space = light_space(centres, radii, sun_direction, resolution)
    if space is None:
        return np.ones(0)
    owner = np.repeat(np.arange(len(cloud_starts) - 1), np.diff(cloud_starts))
    particle, x, y, k, optical_depth = _deposits(space, centres, radii, alpha)
    px, py, ps = space.texel_coordinates(centres)
    whole = _whole(space)
    every = _accumulate(whole, np.zeros(len(x), np.int64), x, y, k, optical_depth)
    every = _sample(whole, every, np.zeros(len(px), np.int64), px, py, ps)
    # each cloud's window: its particles' footprints and the texels they are read at
    _, _, _, x0, x1, y0, y1 = _boxes(space, centres, radii)
    read_x, read_y = np.floor(px - 0.5).astype(np.int64), np.floor(py - 0.5).astype(np.int64)
    low = np.stack([np.minimum(x0, read_x), np.minimum(y0, read_y)], axis=1)
    high = np.stack([np.maximum(x1, read_x + 2), np.maximum(y1, read_y + 2)], axis=1)
    clouds = len(cloud_starts) - 1
    corners = np.full((clouds, 2), np.iinfo(np.int64).max)
    ends = np.zeros((clouds, 2), np.int64)
    np.minimum.at(corners, owner, low)
    np.maximum.at(ends, owner, high)
    corners = np.minimum(corners, ends)  # an empty cloud's window is empty
    own_windows = _Windows(corners, ends - corners)
    own = _sample(own_windows, _accumulate(own_windows, owner[particle], x, y, k, optical_depth), owner, px, py, ps)
    return np.exp(-np.maximum(every - own, 0.0))
