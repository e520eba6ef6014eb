"""The ground's bounce as a light of the clouds' shading model (`[shading] ground_bounce`, docs/shading.md, "The
ground's bounce").

The model lights a cloud by its directional lights (the sun, the skylight from the zenith) and an ambient term, a
radiance arriving alike from every direction.  Under a level Lambertian ground of albedo `a` the lower half of that
sphere is not the ambient but the ground: a radiance `a E / pi`, where E is the ground's irradiance, the lights'
beams on a level surface (`I max(l_y, 0)`) and the ambient's upper hemisphere (`pi A`).  With the bounce on, the
clouds get the ambient's upper half (`A / 2`) and, in place of its lower half, a light from the nadir whose
irradiance on a surface facing down is that hemisphere's, `a E`: the light a cloud's base receives from the ground,
as Harris's skylight from the zenith is the sky's on its top.

The ground under a cloud is in its shadow: the path-traced truth with terrain found a thick cloud's base lit by
little more than the ambient's share of the ground (docs/shading.md, "The ground's bounce").  So each particle's
bounce is that of the ground straight below it (`ground_light_share`): each light's beam there through the clouds'
transmittance toward it (the opacity map the ground's shadows are drawn with, `cloudcore.light.cloud_shadows`), the
ambient's whole.

`a` is the terrain's colour (its ramp's mean where it has one), or the air's ground albedo without a terrain.
"""

from __future__ import annotations

import numpy as np

from cloudcore.light.cloud_shadows import light_space, opacity_map, sample_map
from cloudcore.light.lighting import LEAST_LIGHT, active_lights
from cloudcore.model.scene import Air, Light, Shading, Terrain
from cloudcore.world.terrain import height_at

#: toward the light, as every `Light.direction`: the bounce comes up from the ground
NADIR = (0.0, -1.0, 0.0)
#: texels across the clouds' footprint of the maps that shadow the ground below them (the between-clouds maps')
GROUND_SHADOW_RESOLUTION = 128


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


def ground_light_share(centres, radii, alpha, lights, ambient, terrain: Terrain | None) -> np.ndarray:
    """(n,): the share of the level ground's irradiance (`level_ground_irradiance` of `lights` and `ambient`, summed
    over its channels) that reaches the ground straight below each particle at `centres` (n, 3) of `radii` and
    opacity `alpha` (n,), each light's beam through the transmittance of those particles toward it; the ground is
    `terrain`'s heights, or y = 0 without one.  1 where nothing shadows it, 0 where nothing reaches it."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    whole = float(level_ground_irradiance(lights, ambient).sum())
    if len(centres) == 0 or not whole > 0.0:
        return np.ones(len(centres))
    ground = centres.copy()
    ground[:, 1] = 0.0 if terrain is None else height_at(terrain, centres[:, 0], centres[:, 2])
    reaching = np.full(len(centres), float(np.pi * np.sum(ambient)))
    for light in active_lights(lights):
        beam = max(float(light.direction[1]), 0.0) * float(np.sum(light.color)) * light.intensity
        if beam > 0.0:
            space = light_space(centres, radii, light.direction, GROUND_SHADOW_RESOLUTION)
            depth = sample_map(space, opacity_map(space, centres, radii, alpha), ground)
            reaching += beam * np.exp(-depth)
    return np.clip(reaching / whole, 0.0, 1.0)


def bounce_share(centres, radii, alpha, lights, ambient, terrain: Terrain | None) -> np.ndarray:
    """`ground_light_share` for the clouds' lights and ambient as `cloud_lights` gives them with the bounce on (the
    bounce last, the ambient halved): what multiplies each particle's light from the bounce."""
    return ground_light_share(centres, radii, alpha, tuple(lights)[:-1], 2.0 * np.asarray(ambient), terrain)
