"""The air: Earth's defaults from Hillaire 2020's reference implementation (metres, coefficients per metre)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

Rgb = tuple[float, float, float]


@dataclass(frozen=True)
class AtmosphereParameters:
    """A planet's atmosphere: Rayleigh and Mie scattering falling off exponentially with altitude, ozone
    absorbing in a tent-shaped layer, a Lambertian ground (sebh/UnrealEngineSkyAtmosphere's
    `SetupEarthAtmosphere`)."""

    bottom_radius_m: float = 6_360_000.0
    top_radius_m: float = 6_460_000.0
    rayleigh_scattering: Rgb = (5.802e-6, 13.558e-6, 33.1e-6)
    rayleigh_scale_height_m: float = 8_000.0
    mie_scattering: Rgb = (3.996e-6, 3.996e-6, 3.996e-6)
    mie_extinction: Rgb = (4.440e-6, 4.440e-6, 4.440e-6)
    mie_scale_height_m: float = 1_200.0
    #: Cornette-Shanks asymmetry of the aerosols' phase function
    mie_g: float = 0.8
    ozone_absorption: Rgb = (0.650e-6, 1.881e-6, 0.085e-6)
    #: the ozone's density is 1 at this altitude and falls linearly to 0 half a width away on either side
    ozone_centre_m: float = 25_000.0
    ozone_width_m: float = 30_000.0
    ground_albedo: Rgb = (0.3, 0.3, 0.3)

    @property
    def thickness_m(self) -> float:
        return self.top_radius_m - self.bottom_radius_m

    def with_air(self, mie_density_scale: float, ground_albedo: float) -> AtmosphereParameters:
        """These parameters with the aerosols' density scaled (turbid air: above 1) and a grey ground albedo."""
        return dataclasses.replace(
            self,
            mie_scattering=tuple(mie_density_scale * c for c in self.mie_scattering),
            mie_extinction=tuple(mie_density_scale * c for c in self.mie_extinction),
            ground_albedo=(ground_albedo,) * 3,
        )


EARTH = AtmosphereParameters()
