"""The air at an altitude: densities of its three constituents and the coefficients they give (per metre).

Hillaire 2020's `sampleMediumRGB`; altitudes below the ground read as the ground's, above the top as 0 density
falls there anyway.  The phase functions are per steradian (they integrate to 1 over the sphere), whereas
`cloudcore.light.phase` normalises Harris's to a mean of 1: the same functions divided by 4 pi
(tests/unit/atmosphere/test_atmosphere.py checks that).
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.parameters import AtmosphereParameters


def rayleigh_density(params: AtmosphereParameters, altitude_m) -> np.ndarray:
    return np.exp(-np.maximum(altitude_m, 0.0) / params.rayleigh_scale_height_m)


def mie_density(params: AtmosphereParameters, altitude_m) -> np.ndarray:
    return np.exp(-np.maximum(altitude_m, 0.0) / params.mie_scale_height_m)


def ozone_density(params: AtmosphereParameters, altitude_m) -> np.ndarray:
    """The ozone's tent: 1 at its centre, 0 half its width away and beyond."""
    distance = np.abs(np.asarray(altitude_m, dtype=np.float64) - params.ozone_centre_m)
    return np.maximum(1.0 - distance / (0.5 * params.ozone_width_m), 0.0)


def scattering_coefficients(params: AtmosphereParameters, altitude_m) -> tuple[np.ndarray, np.ndarray]:
    """(Rayleigh, Mie) scattering coefficients (..., 3) per metre at `altitude_m` (...)."""
    altitude = np.asarray(altitude_m, dtype=np.float64)[..., None]
    return (
        rayleigh_density(params, altitude) * np.asarray(params.rayleigh_scattering),
        mie_density(params, altitude) * np.asarray(params.mie_scattering),
    )


def extinction_coefficient(params: AtmosphereParameters, altitude_m) -> np.ndarray:
    """Extinction (..., 3) per metre at `altitude_m` (...): Rayleigh scattering, Mie extinction, ozone absorption."""
    altitude = np.asarray(altitude_m, dtype=np.float64)[..., None]
    return (
        rayleigh_density(params, altitude) * np.asarray(params.rayleigh_scattering)
        + mie_density(params, altitude) * np.asarray(params.mie_extinction)
        + ozone_density(params, altitude) * np.asarray(params.ozone_absorption)
    )


def rayleigh_phase(cos_theta) -> np.ndarray:
    """Rayleigh's phase function per steradian; `cos_theta` 1 straight on."""
    mu = np.asarray(cos_theta, dtype=np.float64)
    return 3.0 / (16.0 * np.pi) * (1.0 + mu * mu)


def cornette_shanks_phase(cos_theta, g: float) -> np.ndarray:
    """Cornette and Shanks's (1992) phase function per steradian, Hillaire's Mie lobe; `cos_theta` 1 straight on."""
    mu = np.clip(np.asarray(cos_theta, dtype=np.float64), -1.0, 1.0)
    k = 3.0 / (8.0 * np.pi) * (1.0 - g * g) / (2.0 + g * g)
    return k * (1.0 + mu * mu) / (1.0 + g * g - 2.0 * g * mu) ** 1.5


#: the isotropic phase function, per steradian
ISOTROPIC_PHASE = 1.0 / (4.0 * np.pi)
