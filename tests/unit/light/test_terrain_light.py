"""The terrain's light (`cloudcore.light.terrain_light`): the gradient's as before, the physical sky's sun, dome
and ground bounce by the normal, and the place of the clouds' shadows."""

import numpy as np
import pytest

from cloudcore.light.lighting import NIGHT_AMBIENT, physical_irradiances, scene_lights
from cloudcore.light.terrain_light import terrain_light
from cloudcore.model.scene import Air, Lighting

UP, DOWN = np.array([[0.0, 1.0, 0.0]]), np.array([[0.0, -1.0, 0.0]])


def light_of(lighting: Lighting):
    return terrain_light(lighting, *scene_lights(lighting))


@pytest.mark.parametrize("hours", [7.0, 15.5, 18.25, 23.0])
def test_the_gradient_lights_the_terrain_as_before(hours):
    """ambient + sum of colour * intensity * max(0, n . l) over the lights, the formula of before."""
    lighting = Lighting(time_of_day=hours, air=Air(sky="gradient"))
    lights, ambient = scene_lights(lighting)
    normals = np.random.default_rng(3).normal(size=(50, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    expected = np.broadcast_to(ambient, (50, 3)).copy()
    for light in lights:
        expected += np.maximum(normals @ light.direction, 0.0)[:, None] * np.asarray(light.color) * light.intensity
    assert np.allclose(light_of(lighting).irradiance(normals), expected, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("hours", [6.5, 12.0, 18.25])
def test_the_physical_sky_lights_the_terrain_by_its_normal(hours):
    """Facing up: the sun's beam by its cosine, the whole sky, the night floor; facing down: the ground's bounce
    alone (its albedo times the level ground's irradiance); a shadowed vertex loses the sun's beam, not the sky."""
    lighting = Lighting(time_of_day=hours)
    direction, sun, sky = physical_irradiances(hours, lighting.air)
    light = light_of(lighting)
    level = sun * max(direction[1], 0.0) + sky
    assert np.allclose(light.irradiance(UP)[0], NIGHT_AMBIENT + level, rtol=1e-9)
    assert np.allclose(light.irradiance(DOWN)[0], NIGHT_AMBIENT + lighting.air.ground_albedo * level, rtol=1e-9)
    shadowed = light.irradiance(UP, sun_visibility=0.0)[0]
    assert np.allclose(shadowed, NIGHT_AMBIENT + sky, rtol=1e-9)


def test_a_slope_toward_the_sun_is_brighter_than_one_away_from_it():
    lighting = Lighting(time_of_day=16.0)
    direction, _, _ = physical_irradiances(16.0, lighting.air)
    across = np.array([direction[0], 0.0, direction[2]]) / np.hypot(direction[0], direction[2])
    toward = (UP[0] + across) / np.sqrt(2.0)
    away = (UP[0] - across) / np.sqrt(2.0)
    lit = light_of(lighting).irradiance(np.stack([toward, away]))
    assert np.all(lit[0] > 1.5 * lit[1])
