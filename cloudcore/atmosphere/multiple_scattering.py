"""The multiple-scattering table psi_ms (Hillaire 2020, section 5.2, `NewMultiScattCS`): the light of every
scattering order past the first that reaches a point, per unit of the sun's irradiance, for an isotropic
phase function.

For each texel (the sun's cosine to the up along u, the altitude along v) 64 directions over the sphere
(8 x 8, stratified as his) are marched to the ground or the top: L_2 is the mean of the sun's light scattered
once toward the point (the lit ground included), f_ms the mean share of light the air around scatters back
toward it; the orders sum as a geometric series, psi_ms = L_2 / (1 - f_ms) (his eq. 9-10).
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.geometry import distance_to_boundary, ray_hits_ground
from cloudcore.atmosphere.parameters import AtmosphereParameters
from cloudcore.atmosphere.scattering import isotropic_in_scattering
from cloudcore.atmosphere.table_sampling import sub_uv_to_unit, texel_centres

MULTIPLE_SCATTERING_TABLE_SIZE = 32
#: directions over the sphere: this squared
SQRT_DIRECTIONS = 8
#: samples a ray (Hillaire: 20)
MULTIPLE_SCATTERING_SAMPLES = 20
#: the lowest and highest texels sit this far inside the air (Hillaire's PLANET_RADIUS_OFFSET)
_INSIDE_M = 10.0


def sphere_directions() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cos theta to the up, sin theta, azimuth) of Hillaire's 64 stratified directions, uniform over the sphere."""
    cells = (np.arange(SQRT_DIRECTIONS) + 0.5) / SQRT_DIRECTIONS
    azimuth, polar = np.meshgrid(2.0 * np.pi * cells, np.arccos(1.0 - 2.0 * cells))
    return np.cos(polar).ravel(), np.sin(polar).ravel(), azimuth.ravel()


def build_multiple_scattering_table(params: AtmosphereParameters, transmittance_table: np.ndarray) -> np.ndarray:
    """(32, 32, 3): psi_ms over (the sun's cosine to the up, altitude)."""
    size = MULTIPLE_SCATTERING_TABLE_SIZE
    u, v = np.meshgrid(sub_uv_to_unit(texel_centres(size), size), sub_uv_to_unit(texel_centres(size), size))
    mu_s = np.clip(2.0 * u - 1.0, -1.0, 1.0)[..., None]
    # a ray depends on the altitude and its direction, not the sun: one march a row serves every sun of the row
    altitude = np.clip(v[:, :1] * params.thickness_m, _INSIDE_M, params.thickness_m - _INSIDE_M)
    r = (params.bottom_radius_m + altitude)[..., None]
    mu, sin_theta, azimuth = sphere_directions()
    # the sun in the plane of the up and the azimuth's zero
    nu = mu * mu_s + sin_theta * np.cos(azimuth) * np.sqrt(np.maximum(1.0 - mu_s * mu_s, 0.0))
    distance = distance_to_boundary(r, mu, params.bottom_radius_m, params.top_radius_m)
    ground = ray_hits_ground(r, mu, params.bottom_radius_m)
    second_order, f_ms = isotropic_in_scattering(
        params, transmittance_table, r, mu, mu_s, nu, distance, MULTIPLE_SCATTERING_SAMPLES, ground
    )
    second_order, f_ms = second_order.mean(axis=-2), f_ms.mean(axis=-2)
    return second_order / (1.0 - np.minimum(f_ms, 0.999))
