"""The planet's ground past the terrain's square (`cloudcore.light.far_ground`): the world pass's sky draws it as the
numpy sky does, the terrain's edge meets it without a line, and it hides a cloud behind it as the terrain would."""

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
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH

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
