"""Light scattered toward the eye along a ray through the air: Hillaire 2020's `IntegrateScatteredLuminance`.

At each sample the sun's light arrives through the transmittance table (0 where the ground hides the sun),
is scattered by Rayleigh and Mie with their phase functions, and the light of every higher order arrives
through the multiple-scattering table (psi_ms, isotropic); each step's source is integrated over the step
with the step's own attenuation ((S - S exp(-sigma dt)) / sigma, Hillaire's slide-28 form, exact for a
constant medium over the step).  `in_scattering` is the sky view's and, given a point's distance, aerial
perspective's: the light the air adds between the eye and the point, and what it lets through.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.atmosphere.geometry import radius_along, ray_hits_ground, sun_cosine_along
from cloudcore.atmosphere.medium import (
    ISOTROPIC_PHASE,
    cornette_shanks_phase,
    extinction_coefficient,
    rayleigh_phase,
    scattering_coefficients,
)
from cloudcore.atmosphere.parameters import AtmosphereParameters
from cloudcore.atmosphere.ray_samples import ray_samples
from cloudcore.atmosphere.table_sampling import sample_bilinear, unit_to_sub_uv
from cloudcore.atmosphere.transmittance import transmittance_to_top

#: the least extinction a step divides by: above the top of the air the densities underflow toward 0
_LEAST_EXTINCTION = 1e-30


@dataclass(frozen=True)
class RayMarch:
    """A ray's samples: where they are, what the air there does, what reaches them from the start.  The sun has
    no part in it, so one march serves every sun direction around the ray (`sunlight_along` adds the sun's)."""

    t: np.ndarray  # (..., S)
    dt: np.ndarray  # (..., S)
    radius: np.ndarray  # (..., S)
    rayleigh: np.ndarray  # (..., S, 3) scattering coefficients
    mie: np.ndarray  # (..., S, 3)
    extinction: np.ndarray  # (..., S, 3)
    #: the transmittance from the ray's start to each step's start (..., S, 3), and over the whole ray (..., 3)
    throughput: np.ndarray
    transmittance: np.ndarray

    def integrate(self, source) -> np.ndarray:
        """(..., 3): the sum over steps of the source (..., S, 3, per metre; broadcast against the ray's
        samples) integrated over each step and attenuated on the way back to the start."""
        extinction = np.maximum(self.extinction, _LEAST_EXTINCTION)
        step_share = -np.expm1(-extinction * self.dt[..., None]) / extinction
        return np.einsum("...sc,...sc->...c", self.throughput * step_share, source)


def march(params: AtmosphereParameters, r, mu, distance, samples: int) -> RayMarch:
    """Sample the rays from radius `r` at cosine `mu` to the up over `distance` (broadcast together)."""
    r, mu, distance = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (r, mu, distance)))
    t, dt = ray_samples(r, mu, distance, samples)
    # a ray marched past the ground (aerial perspective's toward a surface over the curved planet's horizon)
    # meets the air at the ground's density there, not an exponential's extrapolation
    radius = np.maximum(radius_along(r[..., None], mu[..., None], t), params.bottom_radius_m)
    altitude = radius - params.bottom_radius_m
    rayleigh, mie = scattering_coefficients(params, altitude)
    extinction = extinction_coefficient(params, altitude)
    step_depth = extinction * dt[..., None]
    depth_before = np.cumsum(step_depth, axis=-2) - step_depth
    return RayMarch(
        t=t,
        dt=dt,
        radius=radius,
        rayleigh=rayleigh,
        mie=mie,
        extinction=extinction,
        throughput=np.exp(-depth_before),
        transmittance=np.exp(-step_depth.sum(axis=-2)),
    )


def sunlight_along(params: AtmosphereParameters, transmittance_table, ray: RayMarch, r, mu_s, nu):
    """(the sun's cosine to the up at each sample (..., S), its transmittance there, 0 in the ground's shadow
    (..., S, 3)) for the sun at cosine `mu_s` to the up at the rays' start and `nu` to the rays (broadcast
    against the rays' own shape: a march of (rows, 1) serves suns of (rows, columns))."""
    sun_cosine = sun_cosine_along(
        np.asarray(r, dtype=np.float64)[..., None],
        np.asarray(mu_s, dtype=np.float64)[..., None],
        np.asarray(nu, dtype=np.float64)[..., None],
        ray.t,
        ray.radius,
    )
    radius = np.broadcast_to(ray.radius, sun_cosine.shape)
    lit = ~ray_hits_ground(radius, sun_cosine, params.bottom_radius_m)
    return sun_cosine, transmittance_to_top(params, transmittance_table, radius, sun_cosine) * lit[..., None]


def multiple_scattering_lookup(params: AtmosphereParameters, table: np.ndarray, r, mu_s) -> np.ndarray:
    """(..., 3): psi_ms (`multiple_scattering`) at radius `r` for the sun at cosine `mu_s` (`GetMultipleScattering`)."""
    size = table.shape[0]
    u = np.clip(np.asarray(mu_s) * 0.5 + 0.5, 0.0, 1.0)
    v = np.clip((np.asarray(r) - params.bottom_radius_m) / params.thickness_m, 0.0, 1.0)
    return sample_bilinear(table, unit_to_sub_uv(u, size), unit_to_sub_uv(v, size))


def ground_radiance(params: AtmosphereParameters, transmittance_table, r, mu_s) -> np.ndarray:
    """(..., 3): the radiance of the Lambertian ground at radius `r` under the sun at cosine `mu_s`
    (the direct sun only, as in Hillaire's ground term)."""
    sunlight = transmittance_to_top(params, transmittance_table, r, mu_s)
    return sunlight * np.maximum(np.asarray(mu_s), 0.0)[..., None] * np.asarray(params.ground_albedo) / np.pi


def in_scattering(
    params: AtmosphereParameters,
    transmittance_table,
    multiple_scattering_table,
    r,
    mu,
    mu_s,
    nu,
    distance,
    samples: int,
    ground=False,
) -> tuple[np.ndarray, np.ndarray]:
    """(radiance (..., 3), transmittance (..., 3)) over `distance` along the rays (`march`), per unit solar
    irradiance: the sun's single scattering by Rayleigh and Mie, every higher order through psi_ms, and where
    `ground` (...) is true the ground at the ray's end seen through the air."""
    ray = march(params, r, mu, distance, samples)
    sun_cosine, sunlight = sunlight_along(params, transmittance_table, ray, r, mu_s, nu)
    scattering_cosine = np.asarray(nu, dtype=np.float64)[..., None, None]
    single = sunlight * (
        ray.rayleigh * rayleigh_phase(scattering_cosine)
        + ray.mie * cornette_shanks_phase(scattering_cosine, params.mie_g)
    )
    multiple = multiple_scattering_lookup(params, multiple_scattering_table, ray.radius, sun_cosine)
    radiance = ray.integrate(single + multiple * (ray.rayleigh + ray.mie))
    if np.any(ground):
        radiance = radiance + _seen_ground(params, transmittance_table, ray, r, mu, mu_s, nu, distance, ground)
    return radiance, ray.transmittance


def isotropic_in_scattering(params, transmittance_table, r, mu, mu_s, nu, distance, samples, ground):
    """(second-order source L (..., 3), f_ms (..., 3)) along the rays for Hillaire's psi_ms (his eqs. 5-7):
    the sun's light scattered once isotropically toward the start, the lit ground at the end included, and
    the scattering integrated with unit phase (the share of light the air sends back as a next order)."""
    ray = march(params, r, mu, distance, samples)
    _, sunlight = sunlight_along(params, transmittance_table, ray, r, mu_s, nu)
    scattering = ray.rayleigh + ray.mie
    radiance = ray.integrate(sunlight * scattering * ISOTROPIC_PHASE)
    radiance = radiance + _seen_ground(params, transmittance_table, ray, r, mu, mu_s, nu, distance, ground)
    return radiance, ray.integrate(scattering)


def _seen_ground(params, transmittance_table, ray: RayMarch, r, mu, mu_s, nu, distance, ground) -> np.ndarray:
    """(..., 3): the lit ground at the rays' ends through the air, where `ground` (...) is true, else 0."""
    end_radius = radius_along(r, mu, distance)
    end_sun = sun_cosine_along(r, mu_s, nu, distance, end_radius)
    bounced = ray.transmittance * ground_radiance(params, transmittance_table, end_radius, end_sun)
    return np.asarray(ground, dtype=np.float64)[..., None] * bounced
