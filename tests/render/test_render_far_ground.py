"""The planet's ground past the terrain's square (`cloudcore.light.far_ground`): the world pass's sky draws it as the
numpy sky does, the terrain's edge meets it without a line, and it hides a cloud behind it as the terrain would."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.far_ground import far_ground_colour
from cloudcore.light.lighting import scene_lights
from cloudcore.light.sky_background import scene_sky
from cloudcore.light.terrain_light import terrain_light
from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.model.scene import Camera, Cloud, Lighting, Scene, Terrain
from cloudcore.model.settings import FULL_3D
from cloudcore.world.camera import pixel_rays
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH, ball

pytestmark = pytest.mark.gl

#: a patch 20 km square of low hills, no `reach`: its edge 10 km from the origin
PATCH = Terrain(size=(20000.0, 20000.0), resolution=65, height=150.0, seed=7)
HALF_SIDE = 10000.0
LIGHTING = Lighting(time_of_day=15.5)
#: outside the patch, 2 km up, looking at it across the ground past its edge
OUTSIDE = Camera((-16000.0, 2000.0, 0.0), (-6000.0, 600.0, 0.0), 40.0)


def far_ground() -> np.ndarray:
    lights, ambient = scene_lights(LIGHTING)
    return far_ground_colour(PATCH, terrain_light(LIGHTING, lights, ambient))


def ground_hits(camera: Camera) -> np.ndarray:
    """(height, width, 3): where each pixel's ray meets the level y = 0 (nan where it does not)."""
    rays = pixel_rays(camera, RENDER_WIDTH, RENDER_HEIGHT)
    eye = np.asarray(camera.position, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(rays[..., 1] < 0.0, -eye[1] / rays[..., 1], np.nan)
    return eye + t[..., None] * rays


@pytest.fixture(scope="module")
def outside(renderer) -> np.ndarray:
    renderer.render(Scene(camera=OUTSIDE, lighting=LIGHTING, terrain=PATCH), settings=FULL_3D, read_back=False)
    return renderer.context.read_linear_rgb()


def test_the_sky_draws_the_ground_past_the_terrain_as_numpy_does(outside):
    hits = ground_hits(OUTSIDE)
    # the level ground short of the patch (the eye is outside it): the sky's, in front of the terrain
    past = hits[..., 0] < -HALF_SIDE - 300.0
    assert past.mean() > 0.2
    expected = (
        scene_sky(LIGHTING)
        .seen_from(OUTSIDE.position)
        .radiance(pixel_rays(OUTSIDE, RENDER_WIDTH, RENDER_HEIGHT), 1e-3, far_ground=far_ground())
    )
    close = np.abs(outside - expected) <= 0.01 * expected + 1e-3
    assert close.all(axis=-1)[past].mean() > 0.995
    # the ground, not the air at the horizon: greener than the sky's air just over the horizon at the same azimuth
    assert np.all(outside[past][:, 1] > outside[past][:, 2])


def test_the_terrain_s_edge_meets_the_ground_past_it_without_a_line(outside):
    """Down each column across the patch's edge, no step between neighbouring rows larger than the ground's own
    gradient a few rows off the edge (the far ground's air and the terrain's meet; before, the band past the edge
    was the air at the horizon, 20-40 levels off the terrain)."""
    picture = linear_to_srgb8(outside).astype(int)
    hits = ground_hits(OUTSIDE)
    columns = range(RENDER_WIDTH // 4, 3 * RENDER_WIDTH // 4)
    for column in columns:
        edge = int(np.nanargmin(np.abs(hits[:, column, 0] + HALF_SIDE)))  # the row at the patch's edge
        steps = np.abs(np.diff(picture[edge - 6 : edge + 7, column], axis=0)).max(axis=1)
        assert steps.max() <= 3, f"column {column}: steps {steps.tolist()} across the edge at row {edge}"


def test_a_cloud_behind_the_ground_past_the_terrain_is_hidden_by_it(renderer):
    """A cloud under the level of the ground, past the patch, seen from above outside it: the ground in front of
    it hides it as the terrain hides what is behind (the far ground takes its depth)."""
    eye = np.array([-16000.0, 3000.0, 0.0])
    camera = Camera(tuple(eye), (-15000.0, 0.0, 0.0), 40.0)
    rng = np.random.default_rng(2)
    buried = np.column_stack([np.array([-15000.0, -1500.0, 0.0]) + rng.normal(size=(60, 3)) * 80.0, np.full(60, 90.0)])
    pictures = [
        renderer.render(Scene(camera=camera, lighting=LIGHTING, terrain=PATCH, clouds=clouds), settings=FULL_3D)[0]
        for clouds in ((), (Cloud("buried", buried),))
    ]
    assert np.abs(pictures[1].astype(int) - pictures[0].astype(int)).max() <= 1


def shadow_across_the_edge() -> tuple[Scene, np.ndarray]:
    """A cloud 3 km up whose shadow falls across the patch's edge, and the edge's point at its centre's shadow."""
    sun = np.asarray(scene_lights(LIGHTING)[0][0].direction)
    shadow = np.array([-HALF_SIDE, 0.0, 0.0])
    centre = shadow + (3000.0 / sun[1]) * sun
    cloud = ball(centre, particles=800, seed=4)
    # level: the far ground lies at its edge's height, so a hill's edge would step the shadow by its height
    flat = dataclasses.replace(PATCH, height=0.0)
    return Scene(lighting=LIGHTING, terrain=flat, clouds=(cloud,)), shadow


def test_the_clouds_shadow_the_ground_past_the_terrain_as_the_terrain_without_a_seam(renderer):
    """Looked down onto a cloud's shadow across the patch's edge (the cloud out of view, above the eye): the ground
    past the edge is in the shadow as the terrain is, their shadow factors (with over without the shadows) meet at
    the edge; away from the cloud, off the map, the ground past the edge is drawn as without shadows."""
    scene, shadow = shadow_across_the_edge()
    camera = Camera(tuple(shadow + [0.0, 1200.0, 0.0]), tuple(shadow + [0.0, 0.0, 60.0]), 50.0)
    looks = [
        renderer.render(scene, camera=camera, settings=dataclasses.replace(FULL_3D, cloud_shadows=on), read_back=False)
        and renderer.context.read_linear_rgb()
        for on in (True, False)
    ]
    factor = looks[0].mean(axis=-1) / looks[1].mean(axis=-1)
    hits = ground_hits(camera)
    past = hits[..., 0] < -HALF_SIDE
    assert 0.2 < past.mean() < 0.8
    near_edge = np.abs(hits[..., 0] + HALF_SIDE) < 60.0
    shaded = near_edge & (factor < 0.8)
    assert (shaded & past).sum() > 20 and (shaded & ~past).sum() > 20  # the shadow on both sides of the edge
    assert factor[past].min() < 0.6  # as deep as on the terrain
    for row in range(RENDER_HEIGHT):  # no step in the factor across the edge beyond its steps on either side
        edge = int(np.argmin(np.abs(hits[row, :, 0] + HALF_SIDE)))
        across = abs(factor[row, edge + 1] - factor[row, edge - 1])
        beside = np.abs(factor[row, edge - 8 : edge + 9][2:] - factor[row, edge - 8 : edge + 9][:-2])
        assert across <= max(np.delete(beside, 7).max() + 0.02, 0.02), f"row {row}: {factor[row, edge - 8 : edge + 9]}"
    # off the map (the cloud's footprint along the sun), the ground past the edge as without shadows
    away = Camera(OUTSIDE.position, tuple(np.asarray(OUTSIDE.look_at) + [0.0, 0.0, 6000.0]), 40.0)
    pictures = [
        renderer.render(scene, camera=away, settings=dataclasses.replace(FULL_3D, cloud_shadows=on))[0].astype(int)
        for on in (True, False)
    ]
    far = ground_hits(away)[..., 0] < -HALF_SIDE - 300.0
    assert far.mean() > 0.2 and np.array_equal(pictures[0][far], pictures[1][far])
