"""Depth interplay of the world and cloud passes: a hill hides a cloud behind it, not one in front.

Both as full 3D and as impostors (a quad through the cloud's centre, depth-tested like the splats), and as
full 3D composited by the compute pass.
"""

import numpy as np
import pytest

from cloudcore.model.scene import Camera, Cloud, Lighting, Scene, Terrain
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.world.terrain import height_at

pytestmark = pytest.mark.gl

TERRAIN = Terrain(size=(2000.0, 2000.0), resolution=65, height=600.0, seed=3)
EYE = np.array([0.0, 120.0, 0.0])


def puff(centre) -> Cloud:
    rng = np.random.default_rng(1)
    offsets = rng.normal(size=(60, 3)) * 25.0
    return Cloud("puff", np.column_stack([np.asarray(centre) + offsets, np.full(60, 30.0)]))


def line_of_sight_blocked(target) -> bool:
    points = EYE + np.linspace(0.02, 0.98, 400)[:, None] * (np.asarray(target) - EYE)
    return bool(np.any(height_at(TERRAIN, points[:, 0], points[:, 2]) > points[:, 1]))


def scene_with(*clouds, terrain=TERRAIN) -> Scene:
    # look east, up the valley's side, at the ridge
    camera = Camera(tuple(EYE), (1000.0, 250.0, 0.0), 50.0)
    return Scene(camera=camera, lighting=Lighting(time_of_day=12.0), clouds=clouds, terrain=terrain)


#: full 3D as the raster blends it, as impostors, and composited by the compute pass (which cuts each splat
#: at the world's depth itself: `compositing = "compute"`)
DEPTH_SETTINGS = {
    "full": FULL_3D,
    "impostor": RenderSettings(mode="impostor"),
    "compute": RenderSettings(mode="full", splat_order="gpu", compositing="compute"),
}


@pytest.fixture(scope="module", params=list(DEPTH_SETTINGS.values()), ids=list(DEPTH_SETTINGS))
def renders(renderer, request):
    in_front = [330.0, float(height_at(TERRAIN, 330.0, 0.0)) + 100.0, 0.0]
    behind = [980.0, float(height_at(TERRAIN, 980.0, 0.0)) - 180.0, 0.0]
    # the whole of the hidden puff (every particle's top) is out of sight behind the hill
    assert all(line_of_sight_blocked(p[:3] + [0.0, p[3], 0.0]) for p in puff(behind).particles)
    assert not line_of_sight_blocked(in_front)
    settings = request.param
    images = {
        name: renderer.render(scene_with(*clouds), settings=settings)[0]
        for name, clouds in {"none": (), "in_front": (puff(in_front),), "behind": (puff(behind),)}.items()
    }
    images["behind_without_hill"] = renderer.render(scene_with(puff(behind), terrain=None), settings=settings)[0]
    images["none_without_hill"] = renderer.render(scene_with(terrain=None), settings=settings)[0]
    return images


def test_the_hidden_cloud_is_in_view_once_the_hill_is_gone(renders):
    difference = np.abs(renders["behind_without_hill"].astype(int) - renders["none_without_hill"].astype(int))
    assert (difference.max(axis=2) > 10).sum() > 50


def test_a_cloud_behind_the_hill_is_hidden_by_it(renders):
    difference = np.abs(renders["behind"].astype(int) - renders["none"].astype(int))
    assert difference.max() <= 1


def test_a_cloud_in_front_of_the_hill_covers_it(renders):
    difference = np.abs(renders["in_front"].astype(int) - renders["none"].astype(int)).max(axis=2)
    assert (difference > 10).sum() > 50
