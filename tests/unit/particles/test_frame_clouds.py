"""The clouds a frame draws, kept between frames (`cloudcore.particles.frame_clouds`): nothing remade for a frame
like the last, a field's cells kept and carried by the air, Wang's ring's keys stepping with the drift; no GL."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.artist.cloudgen import preset_cloud
from cloudcore.light.illumination import IlluminationCache
from cloudcore.light.lighting import scene_lights
from cloudcore.model.scene import Camera, CloudField, Scene, Wind
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.particles.frame_clouds import FrameClouds

#: a westerly: the clouds drift toward +x
WIND = Wind(bands=((0.0, 10.0, 270.0),))
CAMERA = Camera((0.0, 1500.0, 0.0), (0.0, 1800.0, -3000.0), 60.0)


@pytest.fixture(scope="module")
def two_clouds() -> Scene:
    clouds = tuple(
        dataclasses.replace(preset_cloud("cumulus_humilis", name, centre, seed=seed), sprite=None, artist=None)
        for name, centre, seed in (("left", (-300.0, 1000.0, 0.0), 3), ("right", (500.0, 1100.0, -400.0), 5))
    )
    return Scene(camera=Camera((0.0, 1100.0, 2600.0), (0.0, 1050.0, 0.0), 50.0), clouds=clouds)


def prepared(clouds: FrameClouds, scene: Scene, time_s: float = 0.0, settings: RenderSettings = FULL_3D):
    lights, ambient = scene_lights(scene.lighting)
    return clouds.prepare(scene, scene.camera, scene.lighting, lights, ambient, "exact", settings, time_s, None)


def test_a_frame_like_the_last_remakes_nothing(two_clouds):
    clouds = FrameClouds(IlluminationCache())
    first = prepared(clouds, two_clouds)
    keys = clouds.cloud_keys(first.scene, first.fade_keys, 0.0)
    again = prepared(clouds, two_clouds)
    assert again.particles is first.particles and again.units is first.units and again.motion is None
    assert again.illumination_ms == 0.0 < first.illumination_ms
    assert clouds.cloud_keys(again.scene, again.fade_keys, 0.0) is keys


def test_under_wind_the_clouds_are_carried_and_lit_once(two_clouds):
    clouds = FrameClouds(IlluminationCache())
    windy = dataclasses.replace(two_clouds, wind=WIND)
    rest = prepared(clouds, windy).particles.centres.copy()
    later = prepared(clouds, windy, time_s=30.0)
    np.testing.assert_allclose(later.particles.centres - rest, np.tile([300.0, 0.0, 0.0], (len(rest), 1)), atol=1e-6)
    assert later.illumination_ms == 0.0  # a drift keeps the light
    np.testing.assert_allclose(later.motion.drifts, [[300.0, 0.0, 0.0]] * 2, atol=1e-9)


def test_a_field_s_cells_that_stay_are_the_very_clouds_carried_by_the_air():
    field = CloudField(seed=2, coverage=0.5, cell_size=600.0, rings=1)
    scene = Scene(camera=CAMERA, cloud_field=field, wind=WIND)
    clouds = FrameClouds(IlluminationCache())
    first = prepared(clouds, scene)
    slots, cells = clouds.field_state.slots, dict(clouds.field_state.cells)
    rest = first.units.centres.copy()
    # 200 m east: the eye's place relative to the air moved 200 m west, as if it had flown there
    later = prepared(clouds, scene, time_s=20.0)
    kept = [i for i, key in enumerate(clouds.field_state.slots) if i < len(slots) and key == slots[i] and key]
    assert len(kept) > 10
    assert all(clouds.field_state.cells[slots[i]] is cells[slots[i]] for i in kept)
    np.testing.assert_allclose(
        later.units.centres[kept] - rest[kept], np.tile([200.0, 0.0, 0.0], (len(kept), 1)), atol=1e-6
    )
    weights = clouds.unit_weights([(index,) for index in range(len(later.scene.clouds))])
    assert np.all((weights >= 0.0) & (weights <= 1.0)) and weights.min() < 1.0  # the outer ring fades


def test_wang_s_ring_keys_step_only_when_a_cloud_crossed_a_rebuild_distance(two_clouds):
    clouds = FrameClouds(IlluminationCache())
    windy = dataclasses.replace(two_clouds, wind=WIND)
    settings = RenderSettings(ring_radius=1000.0)
    step_m = settings.ring_rebuild_horizontal * settings.ring_radius
    ring_keys = (("left",), ("right",))
    keys = []
    for time_s in (0.0, 0.2 * step_m / 10.0, 0.4 * step_m / 10.0, 0.6 * step_m / 10.0):
        motion = prepared(clouds, windy, time_s=time_s, settings=settings).motion
        keys.append(clouds.ring_keys_under_wind(ring_keys, motion, settings))
    assert keys[0] is keys[1] is keys[2] and keys[3] != keys[2]  # the first step at half a rebuild distance
    assert clouds.ring_keys_under_wind(ring_keys, None, settings) is ring_keys
    assert clouds.ring_keys_under_wind(ring_keys, motion, RenderSettings(ring_radius=math.inf)) is ring_keys


def test_the_ground_s_bounce_lights_the_clouds_from_below_and_follows_the_terrain(two_clouds):
    """With `[shading] ground_bounce` the frame's clouds get a light from the nadir of the terrain's colour and the
    ambient's upper half; a new terrain colour relights them, and turning it off gives the scene's lights back."""
    from cloudcore.light.ground_bounce import NADIR
    from cloudcore.model.scene import Terrain

    clouds = FrameClouds(IlluminationCache())
    plain = prepared(clouds, two_clouds).particles
    bouncing = dataclasses.replace(
        two_clouds,
        shading=dataclasses.replace(two_clouds.shading, ground_bounce=True),
        terrain=Terrain(color=(0.2, 0.4, 0.1)),
    )
    lit = prepared(clouds, bouncing).particles
    assert len(lit.light_directions) == len(plain.light_directions) + 1
    np.testing.assert_array_equal(lit.light_directions[-1], NADIR)
    np.testing.assert_allclose(lit.ambient, 0.5 * plain.ambient)
    green = lit.light_radiance[-1]
    assert green[1] > green[0] > green[2] and np.any(lit.incident[:, -1] > 0.0)
    greyer = dataclasses.replace(bouncing, terrain=Terrain(color=(0.3, 0.3, 0.3)))
    regrey = prepared(clouds, greyer)
    assert regrey.illumination_ms > 0.0
    np.testing.assert_allclose(regrey.particles.light_radiance[-1] / green, [1.5, 0.75, 3.0], rtol=1e-9)
    back = prepared(clouds, two_clouds).particles
    np.testing.assert_array_equal(back.light_directions, plain.light_directions)
