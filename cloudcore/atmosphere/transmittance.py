"""Optical depth and the transmittance table: how much of the light leaving a point reaches the top of the air.

The table is Hillaire's (and Bruneton 2017's) over (x_mu, x_r): x_r = rho / H, rho the distance from the
point to the horizon, H that from the ground to the top's horizon; x_mu the distance to the top mapped
between its least (straight up) and largest (grazing the ground) at that radius.  It holds the rays that
do not meet the ground; the ground's shadow is tested apart (`geometry.ray_hits_ground`).  Both axes are
stretched onto the texel centres (Hillaire leaves that off as of no real impact; here it halves the error
of rays near the horizon, where the transmittance changes fastest).
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.geometry import distance_to_top, radius_along
from cloudcore.atmosphere.medium import extinction_coefficient
from cloudcore.atmosphere.parameters import AtmosphereParameters
from cloudcore.atmosphere.ray_samples import ray_samples
from cloudcore.atmosphere.table_sampling import sample_bilinear, sub_uv_to_unit, texel_centres, unit_to_sub_uv

#: (width over the direction, height over the altitude): Hillaire's 256 x 64
TRANSMITTANCE_TABLE_SIZE = (256, 64)
#: samples a ray (`ray_samples`)
TRANSMITTANCE_SAMPLES = 64


def optical_depth(params: AtmosphereParameters, r, mu, distance, samples: int = TRANSMITTANCE_SAMPLES) -> np.ndarray:
    """(..., 3): the extinction integrated over `distance` along rays from radius `r` at cosine `mu`."""
    t, dt = ray_samples(r, mu, distance, samples)
    altitude = radius_along(np.asarray(r)[..., None], np.asarray(mu)[..., None], t) - params.bottom_radius_m
    return np.einsum("...sc,...s->...c", extinction_coefficient(params, altitude), dt)


def _horizon_distances(params: AtmosphereParameters, r) -> tuple[np.ndarray, float]:
    """(rho, H): the distance from radius `r` to its horizon on the ground, and from the ground to the top's."""
    bottom, top = params.bottom_radius_m, params.top_radius_m
    big_h = np.sqrt(top * top - bottom * bottom)
    rho = np.sqrt(np.maximum(np.asarray(r, dtype=np.float64) ** 2 - bottom * bottom, 0.0))
    return rho, big_h


def transmittance_uv(params: AtmosphereParameters, r, mu) -> tuple[np.ndarray, np.ndarray]:
    """The table's (u, v) of a ray (`LutTransmittanceParamsToUv`)."""
    r = np.clip(np.asarray(r, dtype=np.float64), params.bottom_radius_m, params.top_radius_m)
    rho, big_h = _horizon_distances(params, r)
    d = distance_to_top(r, mu, params.top_radius_m)
    d_min = params.top_radius_m - r
    d_max = rho + big_h
    width, height = TRANSMITTANCE_TABLE_SIZE
    x_mu = np.clip((d - d_min) / np.maximum(d_max - d_min, 1e-9), 0.0, 1.0)
    return unit_to_sub_uv(x_mu, width), unit_to_sub_uv(rho / big_h, height)


def transmittance_ray(params: AtmosphereParameters, u, v) -> tuple[np.ndarray, np.ndarray]:
    """The (r, mu) of the table's (u, v) (`UvToLutTransmittanceParams`)."""
    width, height = TRANSMITTANCE_TABLE_SIZE
    u, v = sub_uv_to_unit(u, width), sub_uv_to_unit(v, height)
    _, big_h = _horizon_distances(params, params.bottom_radius_m)
    rho = big_h * v
    r = np.sqrt(rho * rho + params.bottom_radius_m**2)
    d_min = params.top_radius_m - r
    d = d_min + u * (rho + big_h - d_min)
    safe_d = np.maximum(d, 1e-9)
    mu = np.where(d > 0.0, (big_h * big_h - rho * rho - d * d) / (2.0 * r * safe_d), 1.0)
    return r, np.clip(mu, -1.0, 1.0)


def build_transmittance_table(params: AtmosphereParameters) -> np.ndarray:
    """(64, 256, 3): the transmittance to the top of the air at each texel's ray."""
    width, height = TRANSMITTANCE_TABLE_SIZE
    u, v = np.meshgrid(texel_centres(width), texel_centres(height))
    r, mu = transmittance_ray(params, u, v)
    return np.exp(-optical_depth(params, r, mu, distance_to_top(r, mu, params.top_radius_m)))


def transmittance_to_top(params: AtmosphereParameters, table: np.ndarray, r, mu) -> np.ndarray:
    """(..., 3): the table's transmittance from radius `r` along cosine `mu` to the top (rays above the
    horizon; below it, the grazing ray's)."""
    return sample_bilinear(table, *transmittance_uv(params, r, mu))
