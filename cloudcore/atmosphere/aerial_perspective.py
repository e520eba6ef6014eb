"""Aerial perspective: the light the air adds between the eye and a surface, and the share of the surface's light
it lets through (Hillaire 2020, section 5.5, his camera volume `RenderCameraVolumePS`), tabled by direction and
distance.

Hillaire's volume is 32 x 32 x 32 froxels over the camera's frustum, remade every frame.  Ours is a volume of the
same size over directions instead, which the camera's turning leaves valid: the view's azimuth from the sun
(squared toward it, as the sky view's), its cosine to the up (square-rooted away from the horizontal, where a
surface's air changes fastest) and the distance, in slices spaced quadratically from 0 (slice 0 is the eye:
nothing added, everything let through) to `MAX_DISTANCE_M`.  It depends on the eye's altitude and the sun
alone, so it is remade when the eye climbs or sinks past `ALTITUDE_STEP_M`, not when it turns or flies level:
built at the altitude knots (`sky.altitude_knots`), blended between them.
Each texel is `scattering.in_scattering` over its distance, marched on its own; a ray into the planet goes on
through air of the ground's density (`scattering.march`), as a flat terrain standing over the curved ground's
horizon sees: stopping it there made neighbouring rows of the volume disagree by 5% in transmittance.
The shaders (terrain.vert.glsl, the splats' and quads') read it as `radiance_and_transmittance` does.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from cloudcore.atmosphere.parameters import AtmosphereParameters
from cloudcore.atmosphere.scattering import in_scattering
from cloudcore.atmosphere.sky import AtmosphereTables, altitude_knots
from cloudcore.atmosphere.sky_view import eye_radius, light_view_cosines
from cloudcore.atmosphere.table_sampling import (
    sample_trilinear,
    sub_uv_to_unit,
    texel_centres,
    unit_to_sub_uv,
)

#: (azimuth, cosine to the up, distance) texels: Hillaire's 32 x 32 x 32
VOLUME_SIZE = (32, 32, 32)
#: the farthest slice; past it a surface gets its air (Hillaire's volume reaches 32 km)
MAX_DISTANCE_M = 64000.0
#: from this fraction of `MAX_DISTANCE_M` on, the terrain's air turns into the sky table's air to the planet's ground
#: (terrain.vert.glsl's FAR_GROUND), which the ground past the terrain is drawn through
FAR_AIR_FROM = 0.875
#: samples along each texel's ray from the eye
SAMPLES = 16
#: the eye's altitude is rounded to this for its volume: within it the volume is reused
ALTITUDE_STEP_M = 100.0
#: the preview's volume, while a slider is dragged in the editor (as its sky-view table is coarser then): 8 slices in
#: distance at 6 samples, built in 3 ms of processor time against 16 slices at 8's 8 (docs/performance.md, "The drag
#: at 4 looks a second")
PREVIEW_VOLUME_SIZE = (16, 16, 8)
PREVIEW_SAMPLES = 6


@dataclass(frozen=True, eq=False)
class AerialPerspective:
    """The volume seen from one altitude under one sun: in-scattered radiance and transmittance, each
    (distance, cosine, azimuth, 3), per unit of the sun's irradiance at the top of the air."""

    params: AtmosphereParameters
    altitude_m: float
    sun_direction: np.ndarray  # (3,) unit, toward the sun
    in_scattered: np.ndarray
    transmittance: np.ndarray

    def radiance_and_transmittance(self, directions, distances) -> tuple[np.ndarray, np.ndarray]:
        """(in-scattered radiance (..., 3), transmittance (..., 3)) toward unit `directions` (..., 3; y up) over
        `distances` (..., metres) from the eye."""
        depth, height, width = self.in_scattered.shape[:3]
        u, v, w = volume_uvw(directions, distances, self.sun_direction, (width, height, depth))
        return (
            sample_trilinear(self.in_scattered, u, v, w),
            sample_trilinear(self.transmittance, u, v, w),
        )


def volume_uvw(directions, distances, sun_direction, size=VOLUME_SIZE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The texture coordinates (u, v, w) in a volume of `size` (width, height, depth) of unit `directions` (..., 3)
    at `distances` (...)."""
    directions = np.asarray(directions, dtype=np.float64)
    width, height, depth = size
    azimuth = np.sqrt(np.clip(0.5 - 0.5 * light_view_cosines(directions, sun_direction), 0.0, 1.0))
    mu = np.clip(directions[..., 1], -1.0, 1.0)
    up = 0.5 + 0.5 * np.sign(mu) * np.sqrt(np.abs(mu))
    slice_position = np.sqrt(np.clip(np.asarray(distances, dtype=np.float64) / MAX_DISTANCE_M, 0.0, 1.0))
    return unit_to_sub_uv(azimuth, width), unit_to_sub_uv(up, height), unit_to_sub_uv(slice_position, depth)


def volume_texels(size=VOLUME_SIZE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(light_view_cosine (width,), mu (height,), distance (depth,)) at the texel centres of a volume of `size`."""
    width, height, depth = size
    azimuth = sub_uv_to_unit(texel_centres(width), width)
    light_view_cosine = 1.0 - 2.0 * azimuth**2
    up = 2.0 * sub_uv_to_unit(texel_centres(height), height) - 1.0
    mu = np.sign(up) * up**2
    distance = MAX_DISTANCE_M * sub_uv_to_unit(texel_centres(depth), depth) ** 2
    return light_view_cosine, mu, distance


def build_aerial_perspective(
    tables: AtmosphereTables, altitude_m: float, sun_direction, preview: bool = False
) -> AerialPerspective:
    """The volume from `altitude_m` with the sun toward unit `sun_direction` (y up); coarser for a `preview`."""
    size, samples = (PREVIEW_VOLUME_SIZE, PREVIEW_SAMPLES) if preview else (VOLUME_SIZE, SAMPLES)
    params = tables.params
    r = eye_radius(params, altitude_m)
    sun = np.asarray(sun_direction, dtype=np.float64)
    mu_s = float(np.clip(sun[1], -1.0, 1.0))
    light_view_cosine, mu, distance = volume_texels(size)
    # one march a row (a cosine to the up) and slice serves every azimuth of that row: (height, 1, depth)
    row_mu = mu[:, None, None]
    nu = row_mu * mu_s + np.sqrt(1.0 - row_mu**2) * np.sqrt(1.0 - mu_s**2) * light_view_cosine[None, :, None]
    radiance, transmittance = in_scattering(
        params, tables.transmittance, tables.multiple_scattering, r, row_mu, mu_s, nu, distance[None, None, :], samples
    )
    # to (depth, height, width, 3), the layout of a 3D texture
    return AerialPerspective(
        params,
        float(altitude_m),
        sun,
        np.ascontiguousarray(np.moveaxis(radiance, 2, 0)),
        np.ascontiguousarray(np.moveaxis(np.broadcast_to(transmittance, radiance.shape), 2, 0)),
    )


def aerial_perspective_from(
    tables: AtmosphereTables, eye_altitude_m: float, sun_direction, preview: bool = False
) -> AerialPerspective:
    """The volume for an eye at `eye_altitude_m` (rounded to `ALTITUDE_STEP_M`, at least 0), coarser for a
    `preview`: the volumes built at the knots around it blended (`sky.altitude_knots`); the last few are kept, so
    an eye flying level or turning reuses one and a frame asks again at no cost."""
    return _aerial_perspective(tables, volume_altitude(eye_altitude_m), tuple(float(c) for c in sun_direction), preview)


def volume_altitude(eye_altitude_m: float) -> float:
    """The altitude of the volume an eye at `eye_altitude_m` draws: rounded to `ALTITUDE_STEP_M`, at least 0."""
    return ALTITUDE_STEP_M * round(max(float(eye_altitude_m), 0.0) / ALTITUDE_STEP_M)


@functools.lru_cache(maxsize=8)
def _aerial_perspective(
    tables: AtmosphereTables, altitude_m: float, sun_direction: tuple, preview: bool
) -> AerialPerspective:
    below, above, share = altitude_knots(altitude_m)
    if share == 0.0:
        return _knot_volume(tables, below, sun_direction, preview)
    low, high = (_knot_volume(tables, knot, sun_direction, preview) for knot in (below, above))
    return AerialPerspective(
        tables.params,
        altitude_m,
        low.sun_direction,
        (1.0 - share) * low.in_scattered + share * high.in_scattered,
        (1.0 - share) * low.transmittance + share * high.transmittance,
    )


@functools.lru_cache(maxsize=8)
def _knot_volume(tables: AtmosphereTables, altitude_m: float, sun_direction: tuple, preview: bool) -> AerialPerspective:
    """The volume built at a knot (`sky.altitude_knots`), which the steps between it and its neighbours blend."""
    return build_aerial_perspective(tables, altitude_m, sun_direction, preview)
