"""The ground's bounce as a light of the clouds' shading (`cloudcore.light.ground_bounce`)."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.ground_bounce import NADIR, bounce_light, cloud_lights, ground_albedo_rgb, level_ground_irradiance
from cloudcore.light.lighting import active_lights, physical_irradiances, scene_lights
from cloudcore.model.scene import Air, Camera, Cloud, Light, Lighting, Scene, Shading, Terrain
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.world.sun import scene_hour
from tests.conftest import assert_file_refused_in_one_line


@pytest.mark.parametrize("hour", [9.0, 12.0, 15.5, 18.25])
def test_a_flat_sunlit_ground_sends_its_albedo_times_the_sun_s_cosine_the_sky_and_the_ambient_s_upper_half(hour):
    """Under the physical sky: a * (E_sun cos(zenith) + E_sky + pi A), A the model's ambient radiance."""
    lighting = Lighting(time_of_day=hour)
    lights, ambient = scene_lights(lighting)
    direction, sun, sky = physical_irradiances(scene_hour(lighting), lighting.air)
    albedo = np.array([0.32, 0.42, 0.22])
    expected = albedo * (sun * max(direction[1], 0.0) + sky + np.pi * ambient)
    light = bounce_light(lights, ambient, albedo)
    assert light.direction == NADIR
    np.testing.assert_allclose(np.array(light.color) * light.intensity, expected, rtol=1e-12)


def test_a_light_below_the_horizon_sends_nothing_down_to_the_ground():
    lights = (Light((0.0, -0.5, np.sqrt(0.75)), (1.0, 1.0, 1.0), 3.0), Light((0.6, 0.8, 0.0), (1.0, 0.5, 0.25), 2.0))
    np.testing.assert_allclose(level_ground_irradiance(lights, (0.0, 0.0, 0.0)), [1.6, 0.8, 0.4], rtol=1e-12)


def test_a_black_night_sends_no_bounce_and_its_light_is_dropped():
    light = bounce_light((Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0), 0.0),), (0.0, 0.0, 0.0), (0.3, 0.3, 0.3))
    assert light.intensity == 0.0 and active_lights((light,)) == ()


def test_off_the_lights_are_the_scene_s_and_on_the_ambient_s_lower_half_becomes_the_bounce():
    lights, ambient = scene_lights(Lighting(time_of_day=15.5))
    off_lights, off_ambient = cloud_lights(lights, ambient, Shading(), (0.3, 0.3, 0.3))
    assert off_lights == tuple(lights) and off_ambient is ambient
    on_lights, on_ambient = cloud_lights(lights, ambient, Shading(ground_bounce=True), (0.3, 0.3, 0.3))
    assert on_lights[: len(lights)] == tuple(lights) and on_lights[-1].direction == NADIR
    np.testing.assert_allclose(on_ambient, 0.5 * np.asarray(ambient), rtol=1e-15)


def test_the_ground_s_albedo_is_the_terrain_s_colour_its_ramp_s_mean_or_the_air_s():
    assert ground_albedo_rgb(None, Air(ground_albedo=0.25)) == (0.25, 0.25, 0.25)
    assert ground_albedo_rgb(Terrain(color=(0.1, 0.2, 0.3)), Air()) == pytest.approx((0.1, 0.2, 0.3))
    ramp = Terrain(color_ramp=((0.0, 0.2, 0.4, 0.0), (500.0, 0.4, 0.0, 0.2)))
    assert ground_albedo_rgb(ramp, Air()) == pytest.approx((0.3, 0.2, 0.1))


def test_a_cloud_s_base_gets_the_bounce_its_top_does_not():
    """Two particles one above the other: the bounce from below reaches the lower whole and the upper through it."""
    cloud = Cloud("pair", [[0.0, 10.0, 0.0, 5.0], [0.0, 0.0, 0.0, 5.0]], optical_depth=6.0)
    shading = Shading(albedo=0.99, eye_pass="saturated", light_pass="octaves", ground_bounce=True)
    lights, ambient = cloud_lights(
        (Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0), 1.0),), (0.1, 0.1, 0.1), shading, (0.3,) * 3
    )
    particles = ParticleBuffer((cloud,), shading, lights, ambient)
    from_below = particles.incident[:, -1]
    assert from_below[1] == pytest.approx(1.0) and from_below[0] < 0.5
    np.testing.assert_allclose(particles.light_radiance[-1], [0.3 * (1.0 + 0.1 * np.pi)] * 3, rtol=1e-12)


def test_the_setting_round_trips_and_is_refused_unless_true_or_false(tmp_path):
    scene = dataclasses.replace(
        Scene(camera=Camera((0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 60.0)), shading=Shading(ground_bounce=True)
    )
    save_scene(scene, tmp_path / "s.toml")
    assert load_scene(tmp_path / "s.toml").shading.ground_bounce is True
    text = (tmp_path / "s.toml").read_text().replace("ground_bounce = true", 'ground_bounce = "yes"')
    (tmp_path / "bad.toml").write_text(text)
    assert_file_refused_in_one_line(tmp_path / "bad.toml", "shading.ground_bounce", "expected true or false, got 'yes'")
