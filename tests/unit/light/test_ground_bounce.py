"""The ground's bounce as a light of the clouds' shading (`cloudcore.light.ground_bounce`)."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.ground_bounce import (
    NADIR,
    bounce_light,
    cloud_lights,
    ground_albedo_rgb,
    ground_light_share,
    level_ground_irradiance,
)
from cloudcore.light.lighting import active_lights, physical_irradiances, scene_lights
from cloudcore.model.scene import Air, Camera, Cloud, Light, Lighting, Scene, Shading, Terrain
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.world.sun import scene_hour
from cloudcore.world.terrain import height_at
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


def test_a_cloud_s_base_gets_the_bounce_its_top_less_and_both_the_ground_s_in_their_shadow():
    """Two particles one above the other, 1 km up, the sun overhead: the ground below them is in their shadow, so
    the lower particle's bounce is the shadowed ground's share of the light, and the upper one's what passes the
    lower too; with the sun low the ground below is in full sun and the lower particle gets all of it."""
    cloud = Cloud("pair", [[0.0, 1010.0, 0.0, 5.0], [0.0, 1000.0, 0.0, 5.0]], optical_depth=6.0)
    shading = Shading(albedo=0.99, eye_pass="saturated", light_pass="octaves", ground_bounce=True)
    for sun, shadowed in (((0.0, 1.0, 0.0), True), ((0.8, 0.6, 0.0), False)):
        lights, ambient = cloud_lights((Light(sun, (1.0, 1.0, 1.0), 1.0),), (0.1, 0.1, 0.1), shading, (0.3,) * 3)
        particles = ParticleBuffer((cloud,), shading, lights, ambient)
        from_below = particles.incident[:, -1]
        share = ground_light_share(particles.centres, particles.radii, particles.alpha, lights[:1], [0.1] * 3, None)
        assert from_below[1] == pytest.approx(share[1], rel=1e-12) and from_below[0] < 0.5 * from_below[1]
        if shadowed:  # through both particles, whose opacity is 1 - exp(-6) each at their centres
            expected = (0.1 * np.pi + np.exp(-12.0)) / (0.1 * np.pi + 1.0)
            assert share[1] == pytest.approx(expected, rel=0.05)
        else:
            assert share[1] == pytest.approx(1.0)
        np.testing.assert_allclose(particles.light_radiance[-1], [0.3 * (sun[1] + 0.1 * np.pi)] * 3, rtol=1e-12)


def test_a_light_s_shadow_falls_where_its_beam_goes():
    """A sun at 45 degrees: an opaque particle 1 km up shadows the ground 1 km downwind, not the ground below it."""
    sun = (Light((-np.sqrt(0.5), np.sqrt(0.5), 0.0), (1.0, 1.0, 1.0), 1.0),)
    centres = [[0.0, 1000.0, 0.0], [1000.0, 1000.0, 0.0]]
    share = ground_light_share(centres, [30.0, 30.0], [0.999, 0.0], sun, (0.0, 0.0, 0.0), None)
    assert share[0] == pytest.approx(1.0) and share[1] < 0.1


def test_the_ground_below_is_the_terrain_s():
    """The sun overhead and an opaque particle under the valley's side, halfway down to y = 0: it shadows the level
    ground at y = 0 below the particle above it, not the terrain's ground, which is above it."""
    terrain = Terrain()
    height = float(height_at(terrain, 2900.0, 50.0))
    assert height > 300.0
    centres = [[2900.0, height + 300.0, 50.0], [2900.0, 0.5 * height, 50.0]]
    sun = (Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0), 1.0),)
    on_terrain = ground_light_share(centres, [30.0, 5.0], [0.0, 0.999], sun, (0.0, 0.0, 0.0), terrain)
    on_level = ground_light_share(centres, [30.0, 5.0], [0.0, 0.999], sun, (0.0, 0.0, 0.0), None)
    assert on_terrain[0] == pytest.approx(1.0) and on_level[0] < 0.1


def test_the_share_is_one_without_light_or_particles_and_finite_at_extremes():
    sun = (Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0), 1.0),)
    assert ground_light_share(np.zeros((0, 3)), [], [], sun, (0.1,) * 3, None).shape == (0,)
    assert ground_light_share([[0.0, 500.0, 0.0]], [10.0], [1.0], (), (0.0,) * 3, None)[0] == 1.0
    share = ground_light_share([[0.0, 1e6, 0.0], [0.0, 500.0, 0.0]], [1e-3, 1e5], [1.0, 1.0], sun, (0.0,) * 3, None)
    assert np.all(np.isfinite(share)) and np.all((share >= 0.0) & (share <= 1.0))


def test_the_setting_round_trips_and_is_refused_unless_true_or_false(tmp_path):
    scene = dataclasses.replace(
        Scene(camera=Camera((0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 60.0)), shading=Shading(ground_bounce=True)
    )
    save_scene(scene, tmp_path / "s.toml")
    assert load_scene(tmp_path / "s.toml").shading.ground_bounce is True
    text = (tmp_path / "s.toml").read_text().replace("ground_bounce = true", 'ground_bounce = "yes"')
    (tmp_path / "bad.toml").write_text(text)
    assert_file_refused_in_one_line(tmp_path / "bad.toml", "shading.ground_bounce", "expected true or false, got 'yes'")
