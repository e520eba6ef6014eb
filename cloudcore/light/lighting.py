"""Time of day to lights: sun colour, skylight, ambient; the sun's direction is `cloudcore.world.sun`'s.

Skylight is a second light from the zenith (Harris section 2.3.1); lights that contribute nothing are
dropped (`active_lights`).  Where a scene's sky is "physical" (`Air.sky`, the default) the light comes
from the atmosphere (`cloudcore.atmosphere`, docs/atmosphere.md): the sun is its beam transmitted to the
scene's origin, the skylight the sky's irradiance on an upward surface, the ambient what the ground
reflects of both, each mapped to the renderer's values by one exposure (`PHYSICAL_EXPOSURE`).  Where it
is "gradient" they are the heuristics of before: the beam after Rayleigh-like extinction over the air
mass (Kasten and Young 1989), golden low in the sky and red at the horizon, fading out over a few
degrees below it; a skylight blue by day and pink at sunset.
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.parameters import EARTH, AtmosphereParameters
from cloudcore.atmosphere.sky import SkyView, atmosphere_tables, sky_irradiance, sky_seen_from, sun_transmittance
from cloudcore.maths.ramps import smoothstep
from cloudcore.model.scene import Air, Light, Lighting
from cloudcore.world.sun import elevation_deg, scene_hour, sun_direction

#: the skies a scene may have (`Air.sky`)
SKIES = ("physical", "gradient")
#: the exposure of the physical sky: the renderer's light intensity for the sun's irradiance at the top of the
#: air, so a white Lambertian surface facing the unattenuated sun is this linear white, and a radiance L (per
#: unit of that irradiance) is pi * PHYSICAL_EXPOSURE * L.  1.5 keeps the default scene's noon near its
#: brightness under the gradient's heuristics, whose noon sun was 0.94 (docs/atmosphere.md)
PHYSICAL_EXPOSURE = 1.5
#: the dimmest light the physical sky gives: a third of the darkest step of 8-bit sRGB (1 / 255 / 12.92)
LEAST_LIGHT = 1e-4

#: extinction per unit air mass, RGB: blue is scattered out first.
BEAM_EXTINCTION = np.array([0.035, 0.075, 0.19])
#: below this elevation (degrees) the sun is gone.
SUN_FADE_DEG = -4.0
NIGHT_AMBIENT = np.array([0.012, 0.016, 0.035])


def air_mass(elevation: float) -> float:
    """Kasten-Young relative air mass; the horizon value below it (the beam is faded there)."""
    e = max(elevation, 0.0)
    return 1.0 / (np.sin(np.radians(e)) + 0.50572 * (e + 6.07995) ** -1.6364)


def sun_beam(elevation: float) -> tuple[np.ndarray, float]:
    """(colour normalised to a max channel of 1, intensity) of the direct sun."""
    transmitted = np.exp(-BEAM_EXTINCTION * air_mass(elevation))
    peak = float(transmitted.max())
    return transmitted / peak, peak * smoothstep(SUN_FADE_DEG, 0.0, elevation)


def golden_hour(elevation: float) -> float:
    """1 with the sun on the horizon, 0 once it is 15 degrees up (and at night)."""
    return smoothstep(-6.0, 0.0, elevation) * (1.0 - smoothstep(2.0, 15.0, elevation))


def sky_colors(hours: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear RGB (zenith, horizon) of the sky background, consistent with the sun."""
    elevation = elevation_deg(sun_direction(hours))
    day = smoothstep(-8.0, 6.0, elevation)
    sunset = golden_hour(elevation)
    zenith = NIGHT_AMBIENT * 0.8 + day * np.array([0.16, 0.32, 0.72])
    horizon = NIGHT_AMBIENT + day * np.array([0.55, 0.68, 0.85])
    horizon = (1 - sunset) * horizon + sunset * np.array([0.95, 0.52, 0.30]) * max(day, 0.35)
    zenith = (1 - 0.5 * sunset) * zenith + 0.5 * sunset * np.array([0.35, 0.30, 0.55]) * day
    return zenith, horizon


def sky_gradient(directions, zenith, horizon) -> np.ndarray:
    """Linear RGB (..., 3) of the sky background seen along unit `directions` (..., 3).

    The horizon colour at and below the horizon line, the zenith colour straight up, and between them
    by the square root of the ray's height, which keeps the pale band near the horizon narrow; the
    world pass draws the same (shaders/sky.frag.glsl, `sky`).
    """
    height = np.sqrt(np.clip(np.asarray(directions, dtype=np.float64)[..., 1:2], 0.0, 1.0))
    return (1.0 - height) * np.asarray(horizon, dtype=np.float64) + height * np.asarray(zenith, dtype=np.float64)


def atmosphere_parameters(air: Air) -> AtmosphereParameters:
    """Earth's atmosphere with a scene's aerosols and ground."""
    return EARTH.with_air(air.mie_density_scale, air.ground_albedo)


def physical_sky(hours: float, air: Air, preview: bool = False) -> SkyView:
    """The atmosphere's sky over the scene's origin at `hours` (a coarser table for a `preview`)."""
    return sky_seen_from(atmosphere_parameters(air), air.origin_altitude_m, sun_direction(hours), preview)


def physical_sun(hours: float, air: Air) -> np.ndarray:
    """(3,): the sun's irradiance reaching the scene's origin at `hours`, in the renderer's values."""
    tables = atmosphere_tables(atmosphere_parameters(air))
    return PHYSICAL_EXPOSURE * sun_transmittance(tables, air.origin_altitude_m, sun_direction(hours))


def daylight(hours: float, air: Air = Air()) -> tuple[tuple[Light, ...], np.ndarray]:
    """Sun and skylight for `hours`, and the ambient term (Harris section 2.3.1), from the scene's air."""
    if air.sky == "physical":
        return _physical_daylight(hours, air)
    direction = sun_direction(hours)
    elevation = elevation_deg(direction)
    sun_color, sun_intensity = sun_beam(elevation)
    zenith, horizon = sky_colors(hours)
    sunset = golden_hour(elevation)
    sky_tint = (1 - sunset) * np.array([0.55, 0.70, 1.0]) + sunset * np.array([1.0, 0.55, 0.65])
    sky_intensity = 0.35 * smoothstep(-8.0, 8.0, elevation)
    lights = (
        Light(tuple(direction), tuple(sun_color), sun_intensity),
        Light((0.0, 1.0, 0.0), tuple(sky_tint), sky_intensity),
    )
    ambient = NIGHT_AMBIENT + 0.25 * (zenith + horizon) * 0.5
    return lights, ambient


def physical_irradiances(hours: float, air: Air) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(the sun's direction, its irradiance reaching the scene's origin, the sky's on an upward surface there)
    at `hours`, each (3,), irradiances in the renderer's values."""
    direction = sun_direction(hours)
    tables = atmosphere_tables(atmosphere_parameters(air))
    sky = PHYSICAL_EXPOSURE * sky_irradiance(tables, air.origin_altitude_m, direction)
    return direction, physical_sun(hours, air), sky


def ground_irradiance(direction, sun, sky) -> np.ndarray:
    """(3,): the irradiance on the level ground under the sun toward `direction` and the sky."""
    return sun * max(float(direction[1]), 0.0) + sky


def _physical_daylight(hours: float, air: Air) -> tuple[tuple[Light, ...], np.ndarray]:
    """The atmosphere's light: the sun's beam, the sky's irradiance on an upward surface as the skylight
    from the zenith, and as the ambient the light the ground reflects (a Lambertian ground of the air's
    albedo under both) spread over the whole sphere, half of it below: the skylight gives the clouds'
    tops their share of the sky, the ambient their undersides theirs of the ground."""
    direction, sun, sky = physical_irradiances(hours, air)
    ambient = NIGHT_AMBIENT + 0.5 * air.ground_albedo * ground_irradiance(direction, sun, sky)
    lights = (_light(direction, sun), _light((0.0, 1.0, 0.0), sky))
    return lights, ambient


def _light(direction, irradiance: np.ndarray) -> Light:
    """A light of `irradiance` (3,): its colour normalised to a largest channel of 1, and that channel; 0 below
    LEAST_LIGHT, so that a night sky's traces cost no shading pass (`active_lights`)."""
    peak = float(irradiance.max())
    if peak < LEAST_LIGHT:
        return Light(tuple(float(c) for c in direction), (1.0, 1.0, 1.0), 0.0)
    return Light(tuple(float(c) for c in direction), tuple(float(c) for c in irradiance / peak), peak)


def scene_lights(lighting: Lighting) -> tuple[tuple[Light, ...], np.ndarray]:
    """The lights and ambient a scene's lighting section stands for."""
    if lighting.lights:
        ambient = NIGHT_AMBIENT if lighting.ambient is None else np.asarray(lighting.ambient, float)
        return lighting.lights, ambient
    lights, ambient = daylight(scene_hour(lighting), lighting.air)
    return lights, (ambient if lighting.ambient is None else np.asarray(lighting.ambient, float))


def active_lights(lights) -> tuple[Light, ...]:
    """Lights that contribute something: no shading pass for the rest."""
    return tuple(light for light in lights if light.intensity > 0 and max(light.color) > 0)
