"""The terrain's tiles as the world pass draws them: their back faces culled, the skirts' faces into their own tiles
too, and the skirts still close every gap between tiles of different sizes (`cloudcore.world.terrain_tiles`)."""

import dataclasses

import numpy as np
import pytest

from cloudcore.model.scene import Air, Camera, Lighting, Scene
from cloudcore.model.settings import RenderSettings
from cloudcore.scenes.files import load_scene
from tests.conftest import VALLEY

pytestmark = pytest.mark.gl

VALLEY_TERRAIN = dataclasses.replace(load_scene(VALLEY).terrain, reach=20000.0)
#: the plain sky, without the air: a pixel the terrain leaves is exactly the sky's
PLAIN = RenderSettings(aerial_perspective=False, cloud_shadows=False, light_shafts=False)
LIGHTING = Lighting(time_of_day=15.5, air=Air(sky="gradient"))


def picture(renderer, camera: Camera, terrain) -> np.ndarray:
    renderer.render(Scene(camera=camera, lighting=LIGHTING, terrain=terrain), settings=PLAIN, read_back=False)
    return renderer.context.read_linear_rgb()


@pytest.mark.parametrize("height", [120.0, 600.0, 2500.0])
@pytest.mark.parametrize("heading_deg", [0.0, 70.0, 160.0, 250.0])
def test_the_culled_terrain_leaves_no_hole(renderer, height, heading_deg):
    """From level eyes over the valley (a screen column is then a vertical plane, in which a heightfield seen
    from above it hides everything under its first ground), each column is ground from where the ground starts
    down to the bottom: no sky shows through a crack between tiles or a culled face."""
    heading = np.radians(heading_deg)
    eye = np.array([400.0 * np.cos(heading), height, 300.0 * np.sin(heading)])
    ahead = eye + 1000.0 * np.array([np.sin(heading), 0.0, -np.cos(heading)])
    camera = Camera(tuple(eye), tuple(ahead), 70.0)
    ground = picture(renderer, camera, VALLEY_TERRAIN)
    sky = picture(renderer, camera, None)
    is_sky = np.all(ground == sky, axis=-1)  # (rows top first, columns)
    below_ground = np.maximum.accumulate(~is_sky, axis=0)  # at or below the column's first ground pixel
    holes = np.count_nonzero(below_ground & is_sky)
    assert np.count_nonzero(~is_sky) > 0.2 * is_sky.size  # the view holds ground
    assert holes == 0, f"{holes} sky pixels under the ground"
