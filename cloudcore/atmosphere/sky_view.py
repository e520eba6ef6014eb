"""The sky-view table: the sky's radiance seen from one altitude for one sun, over the view's zenith angle and
its azimuth from the sun (Hillaire 2020, section 5.3, `SkyViewLutPS`), and the lookups that read it.

The zenith angle is mapped non-linearly (his `NONLINEARSKYVIEWLUT`): the upper half of the table runs from the
zenith to the horizon and the lower half from the horizon to the nadir, each squared toward the horizon
where the sky changes fastest; the azimuth is squared toward the sun.  Rays below the horizon end on the
ground: the table holds the air in front of it alone (his sky view leaves the ground black), and each of its rows
the air's transmittance to the ground, so that the renderer lays its own ground's colour behind the air (the far
ground past a scene's terrain: `cloudcore.light.far_ground`).  Each half is read without the other's rows: the
light changes at the horizon from the air's to the ground's, which filtering across it would blur into a band.
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.geometry import distance_to_boundary, ray_hits_ground
from cloudcore.atmosphere.parameters import AtmosphereParameters
from cloudcore.atmosphere.scattering import in_scattering
from cloudcore.atmosphere.table_sampling import sample_bilinear, sub_uv_to_unit, texel_centres, unit_to_sub_uv

#: (width over the azimuth, height over the zenith angle): Hillaire's 192 x 108
SKY_VIEW_TABLE_SIZE = (192, 108)
#: samples a ray (Hillaire: 4 to 14 by its length, in his real-time sky view; 30 in his reference)
SKY_VIEW_SAMPLES = 24
#: the preview's table, while a slider is dragged in the editor (as the clouds' light is a coarse raster then):
#: a twelfth of the work, its rays a few per cent off near the horizon; its rows matter more than its columns (at
#: 48 x 27 the 99th percentile's error was 3.2-3.8%, at 48 x 36 2.3-2.6%: docs/performance.md, "The drag at 4
#: looks a second")
PREVIEW_TABLE_SIZE = (48, 36)
PREVIEW_SAMPLES = 12


def horizon_angles(params: AtmosphereParameters, r) -> tuple[np.ndarray, np.ndarray]:
    """(beta, the zenith angle of the horizon): beta the horizon's angle below the horizontal (the shaders
    take both as uniforms to read the table as `sky_view_uv` does)."""
    cos_beta = np.sqrt(np.maximum(1.0 - (params.bottom_radius_m / r) ** 2, 0.0))
    beta = np.arccos(np.clip(cos_beta, -1.0, 1.0))
    return beta, np.pi - beta


def sky_view_uv(
    params: AtmosphereParameters, r, mu, light_view_cosine, size=SKY_VIEW_TABLE_SIZE
) -> tuple[np.ndarray, np.ndarray]:
    """The (u, v) in a table of `size` (width, height) of a view of cosine `mu` to the up and `light_view_cosine`
    of its azimuth from the sun's, seen from radius `r` (`SkyViewLutParamsToUv`)."""
    width, height = size
    beta, zenith_horizon = horizon_angles(params, r)
    zenith_angle = np.arccos(np.clip(mu, -1.0, 1.0))
    above = np.clip(1.0 - zenith_angle / zenith_horizon, 0.0, 1.0)
    below = np.clip((zenith_angle - zenith_horizon) / np.maximum(beta, 1e-12), 0.0, 1.0)
    ground = ray_hits_ground(r, mu, params.bottom_radius_m)
    v = np.where(ground, 0.5 * np.sqrt(below) + 0.5, 0.5 * (1.0 - np.sqrt(above)))
    # each half within its own rows' centres: the last row over the horizon is (height / 2 - 1) / (height - 1) of
    # the unit range, the first below it (height / 2) / (height - 1)
    first_ground, last_sky = (height // 2) / (height - 1.0), (height // 2 - 1) / (height - 1.0)
    v = np.where(ground, np.maximum(v, first_ground), np.minimum(v, last_sky))
    u = np.sqrt(np.clip(0.5 - 0.5 * np.asarray(light_view_cosine), 0.0, 1.0))
    return unit_to_sub_uv(u, width), unit_to_sub_uv(v, height)


def sky_view_directions(
    params: AtmosphereParameters, r: float, size=SKY_VIEW_TABLE_SIZE
) -> tuple[np.ndarray, np.ndarray]:
    """(mu, light_view_cosine) (height, width) of the texels of a table of `size` from radius `r`
    (`UvToSkyViewLutParams`)."""
    width, height = size
    u, v = np.meshgrid(sub_uv_to_unit(texel_centres(width), width), sub_uv_to_unit(texel_centres(height), height))
    beta, zenith_horizon = horizon_angles(params, r)
    above = 1.0 - (1.0 - np.clip(2.0 * v, 0.0, 1.0)) ** 2
    below = np.clip(2.0 * v - 1.0, 0.0, 1.0) ** 2
    mu = np.where(v < 0.5, np.cos(zenith_horizon * above), np.cos(zenith_horizon + beta * below))
    return mu, -(2.0 * np.clip(u, 0.0, 1.0) ** 2 - 1.0)


def eye_radius(params: AtmosphereParameters, altitude_m: float) -> float:
    """The distance from the centre of an eye at `altitude_m`, kept within the air (the tables' range)."""
    return float(np.clip(params.bottom_radius_m + altitude_m, params.bottom_radius_m, params.top_radius_m))


def build_sky_view_table(
    params: AtmosphereParameters,
    transmittance_table,
    multiple_scattering_table,
    altitude_m: float,
    sun_cosine: float,
    preview: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """(radiance (108, 192, 3), transmittance (108, 3)): the light the air sends along each view per unit solar
    irradiance seen from `altitude_m` with the sun at cosine `sun_cosine` to the up, to the ground below the
    horizon (the ground itself left out), and each row's transmittance to the ray's end (the ground, or the top of
    the air); (36, 48, 3) and (36, 3) with fewer samples for a `preview`."""
    size, samples = (PREVIEW_TABLE_SIZE, PREVIEW_SAMPLES) if preview else (SKY_VIEW_TABLE_SIZE, SKY_VIEW_SAMPLES)
    r = eye_radius(params, altitude_m)
    mu, light_view_cosine = sky_view_directions(params, r, size)
    mu_s = float(np.clip(sun_cosine, -1.0, 1.0))
    nu = mu * mu_s + np.sqrt(np.maximum(1.0 - mu * mu, 0.0)) * np.sqrt(1.0 - mu_s * mu_s) * light_view_cosine
    # a row's rays differ by their azimuth from the sun alone: one march a row (its first column) serves them all
    row_mu = mu[:, :1]
    distance = distance_to_boundary(r, row_mu, params.bottom_radius_m, params.top_radius_m)
    radiance, transmittance = in_scattering(
        params, transmittance_table, multiple_scattering_table, r, row_mu, mu_s, nu, distance, samples
    )
    return radiance, transmittance[:, 0]


def light_view_cosines(directions, sun_direction) -> np.ndarray:
    """(...): the cosine of the azimuth between `directions` (..., 3) and the sun's, y up (1 where either is
    vertical)."""
    directions = np.asarray(directions, dtype=np.float64)
    sun = np.asarray(sun_direction, dtype=np.float64)
    across = directions[..., 0] * sun[0] + directions[..., 2] * sun[2]
    lengths = np.hypot(directions[..., 0], directions[..., 2]) * np.hypot(sun[0], sun[2])
    return np.where(lengths > 1e-12, np.clip(across / np.maximum(lengths, 1e-12), -1.0, 1.0), 1.0)


def sky_view_lookup(params: AtmosphereParameters, table, altitude_m: float, directions, sun_direction) -> np.ndarray:
    """(..., channels): `table` (height, width, channels), built for this altitude and the sun at unit
    `sun_direction`, along unit `directions` (..., 3; y up); a table of one column (the transmittance of
    `build_sky_view_table`'s rows, (height, 1, channels)) by the row alone."""
    directions = np.asarray(directions, dtype=np.float64)
    height, width = table.shape[:2]
    u, v = sky_view_uv(
        params,
        eye_radius(params, altitude_m),
        directions[..., 1],
        light_view_cosines(directions, sun_direction),
        (width, height),
    )
    return sample_bilinear(table, u, v)
