"""The ground's bounce as a light of the clouds' shading model (`[shading] ground_bounce`, docs/shading.md, "The
ground's bounce").

The model lights a cloud by its directional lights (the sun, the skylight from the zenith) and an ambient term, a
radiance arriving alike from every direction.  Under a level Lambertian ground of albedo `a` the lower half of that
sphere is not the ambient but the ground: a radiance `a E / pi`, where E is the ground's irradiance, the lights'
beams on a level surface (`I max(l_y, 0)`) and the ambient's upper hemisphere (`pi A`).  With the bounce on, the
clouds get the ambient's upper half (`A / 2`) and, in place of its lower half, a light from the nadir whose
irradiance on a surface facing down is that hemisphere's, `a E`: the light a cloud's base receives from the ground,
as Harris's skylight from the zenith is the sky's on its top.  The clouds' shadows on the ground are not in E (the
ground a cloud's base sees reaches kilometres around it; the truth with terrain measures what that leaves out).

`a` is the terrain's colour (its ramp's mean where it has one), or the air's ground albedo without a terrain.
"""

from __future__ import annotations

import numpy as np

from cloudcore.light.lighting import LEAST_LIGHT, active_lights
from cloudcore.model.scene import Air, Light, Shading, Terrain

#: toward the light, as every `Light.direction`: the bounce comes up from the ground
NADIR = (0.0, -1.0, 0.0)


def ground_albedo_rgb(terrain: Terrain | None, air: Air) -> tuple[float, float, float]:
    """(3,) the ground's reflectance under the clouds: the terrain's colour (the mean of its ramp's colours where it
    has a ramp), or the air's grey ground albedo where the scene has no terrain."""
    if terrain is None:
        return (float(air.ground_albedo),) * 3
    if terrain.color_ramp:
        return tuple(float(c) for c in np.mean([row[1:] for row in terrain.color_ramp], axis=0))
    return tuple(float(c) for c in terrain.color)


def level_ground_irradiance(lights, ambient) -> np.ndarray:
    """(3,): the irradiance on level ground under `lights` (their beams by the cosine of their height) and an
    `ambient` radiance over the upper hemisphere (pi times it)."""
    irradiance = np.pi * np.asarray(ambient, dtype=np.float64)
    for light in active_lights(lights):
        irradiance = irradiance + max(float(light.direction[1]), 0.0) * np.asarray(light.color) * light.intensity
    return irradiance


def bounce_light(lights, ambient, albedo) -> Light:
    """The ground's bounce as a light from the nadir: irradiance `albedo` (3,) times the level ground's under
    `lights` and `ambient` (`level_ground_irradiance`); of intensity 0 (dropped by `active_lights`) below
    `LEAST_LIGHT`."""
    irradiance = np.asarray(albedo, dtype=np.float64) * level_ground_irradiance(lights, ambient)
    peak = float(irradiance.max())
    if not peak >= LEAST_LIGHT:
        return Light(NADIR, (1.0, 1.0, 1.0), 0.0)
    return Light(NADIR, tuple(float(c) for c in irradiance / peak), peak)


def cloud_lights(lights, ambient, shading: Shading, albedo) -> tuple[tuple[Light, ...], np.ndarray]:
    """The lights and ambient the clouds are shaded with: the scene's (`scene_lights`), or with
    `shading.ground_bounce` the ambient's upper half and the ground's bounce (`bounce_light`, of the ground's
    `albedo` (3,), `ground_albedo_rgb`) after the scene's lights."""
    if not shading.ground_bounce:
        return tuple(lights), ambient
    ambient = np.asarray(ambient, dtype=np.float64)
    return (*lights, bounce_light(lights, ambient, albedo)), 0.5 * ambient
