"""The light the terrain receives, by its normal: the directional lights (n . l), and under the physical sky the
sky's dome and the ground's bounce as hemisphere terms, at every time of day.

An isotropic sky of irradiance E_sky on an upward surface gives a surface of normal n E_sky (1 + n_y) / 2; the
ground below, a Lambertian reflector of the air's albedo under the sun and the sky, gives it
albedo (E_sun cos + E_sky) (1 - n_y) / 2.  The gradient sky keeps the lights of before (its skylight a light
from the zenith, n . l) and its ambient.  The clouds' shadows fall in the sun's beam alone: the world pass takes
the sun's part (`sun_irradiance`) apart from the rest (`unshadowed_irradiance`) and scales it per
pixel by the clouds' transmittance map (`cloudcore.light.cloud_shadows`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.light.lighting import NIGHT_AMBIENT, active_lights, ground_irradiance, physical_irradiances
from cloudcore.model.scene import Light, Lighting
from cloudcore.world.sun import scene_hour


@dataclass(frozen=True)
class TerrainLight:
    """Directional lights (the first the sun, which a shadow dims), the sky's dome and the ground's bounce
    (irradiances (3,) on a surface facing up and down), and a floor every normal gets."""

    lights: tuple[Light, ...]
    sky_dome: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ground_bounce: tuple[float, float, float] = (0.0, 0.0, 0.0)
    floor: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def irradiance(self, normals, sun_visibility=1.0) -> np.ndarray:
        """(n, 3): the irradiance on surfaces of unit `normals` (n, 3), the sun's beam times `sun_visibility`
        (a scalar or (n,))."""
        normals = np.asarray(normals, dtype=np.float64)
        visibility = np.broadcast_to(np.asarray(sun_visibility, dtype=np.float64), normals.shape[:1])[:, None]
        return self.unshadowed_irradiance(normals) + visibility * self.sun_irradiance(normals)

    def sun_irradiance(self, normals) -> np.ndarray:
        """(n, 3): the first light's (the sun's) beam on surfaces of unit `normals`, the part the clouds shadow."""
        normals = np.asarray(normals, dtype=np.float64)
        return _beam(self.lights[:1], normals)

    def unshadowed_irradiance(self, normals) -> np.ndarray:
        """(n, 3): the rest of `irradiance`, which no shadow dims: the sky's dome, the ground's bounce, the floor
        and the lights after the first."""
        normals = np.asarray(normals, dtype=np.float64)
        up = normals[:, 1:2]
        return (
            np.asarray(self.floor)
            + 0.5 * (1.0 + up) * np.asarray(self.sky_dome)
            + 0.5 * (1.0 - up) * np.asarray(self.ground_bounce)
            + _beam(self.lights[1:], normals)
        )


def _beam(lights, normals: np.ndarray) -> np.ndarray:
    """(n, 3): the directional `lights` that give light on surfaces of unit `normals`, by n . l."""
    irradiance = np.zeros((len(normals), 3))
    for light in active_lights(lights):
        cosine = np.maximum(normals @ np.asarray(light.direction, dtype=np.float64), 0.0)
        irradiance += cosine[:, None] * np.asarray(light.color) * light.intensity
    return irradiance


def terrain_light(lighting: Lighting, lights, ambient) -> TerrainLight:
    """What lights the terrain under `lighting`, whose lights and ambient (`scene_lights`) are `lights` and
    `ambient`: the physical sky's sun, dome and bounce where the scene takes its light from the time of day,
    else the lights and the ambient as given."""
    if lighting.air.sky != "physical" or lighting.lights:
        return TerrainLight(tuple(lights), floor=tuple(float(c) for c in ambient))
    direction, sun, sky = physical_irradiances(scene_hour(lighting), lighting.air)
    ground = lighting.air.ground_albedo * ground_irradiance(direction, sun, sky)
    # an ambient the scene sets stands for what the model leaves out, as it does for the clouds
    floor = NIGHT_AMBIENT if lighting.ambient is None else ambient
    return TerrainLight(
        (lights[0],),
        sky_dome=tuple(float(c) for c in sky),
        ground_bounce=tuple(float(c) for c in ground),
        floor=tuple(float(c) for c in floor),
    )
