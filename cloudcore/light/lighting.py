"""Time of day to lights: sun colour, skylight, ambient; the sun's direction is `cloudcore.sun`'s.

Sun colour is the direct beam after Rayleigh-like extinction over the air mass
(Kasten and Young 1989), so it turns golden low in the sky and red at the
horizon; below the horizon it fades out over a few degrees.  Skylight is a
second light from the zenith (Harris section 2.3.1), blue by day and pink at
sunset; lights that contribute nothing are dropped (`active_lights`).
"""

from __future__ import annotations

import numpy as np

from cloudcore.ramps import smoothstep
from cloudcore.scene import Light, Lighting
from cloudcore.sun import elevation_deg, scene_hour, sun_direction

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
    world pass draws the same (shaders/world.frag.glsl, `sky`).
    """
    height = np.sqrt(np.clip(np.asarray(directions, dtype=np.float64)[..., 1:2], 0.0, 1.0))
    return (1.0 - height) * np.asarray(horizon, dtype=np.float64) + height * np.asarray(zenith, dtype=np.float64)


def daylight(hours: float) -> tuple[tuple[Light, ...], np.ndarray]:
    """Sun and skylight for `hours`, and the ambient term (Harris section 2.3.1)."""
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


def scene_lights(lighting: Lighting) -> tuple[tuple[Light, ...], np.ndarray]:
    """The lights and ambient a scene's lighting section stands for."""
    if lighting.lights:
        ambient = NIGHT_AMBIENT if lighting.ambient is None else np.asarray(lighting.ambient, float)
        return lighting.lights, ambient
    lights, ambient = daylight(scene_hour(lighting))
    return lights, (ambient if lighting.ambient is None else np.asarray(lighting.ambient, float))


def active_lights(lights) -> tuple[Light, ...]:
    """Lights that contribute something: no shading pass for the rest."""
    return tuple(light for light in lights if light.intensity > 0 and max(light.color) > 0)
