"""Golden images of the full-3D renderer on the default scene at 160x120 (tolerance and the
command that regenerates them: tests/goldens.py)."""

import dataclasses

import pytest

from cloudcore.maths.paths import sample
from cloudcore.measure.imagecompare import compare, diff_image
from cloudcore.model.scene import Camera, Scene
from cloudcore.model.settings import FULL_3D
from cloudcore.scenes.files import load_scene
from cloudcore.world.sun import sun_direction
from tests.conftest import VALLEY
from tests.goldens import MAX_ABS, MIN_PSNR_DB, check_golden


@pytest.fixture(scope="module")
def valley():
    return load_scene(VALLEY)


def into_the_sun(scene: Scene) -> Camera:
    """Behind the cloud nearest the start, looking through it toward the 15:30 sun."""
    heart = scene.clouds[0].centres.mean(axis=0)
    toward_sun = sun_direction(15.5)
    eye = heart - 900.0 * toward_sun
    return Camera(tuple(eye), tuple(heart + 100.0 * toward_sun), 60.0)


def inside_a_cloud(scene: Scene) -> Camera:
    at = sample(scene.camera_path("flythrough").keys, 9.0)  # the path's first cloud
    return Camera(tuple(at[:3]), tuple(at[3:]), 60.0)


VIEWS = {
    "default_view": lambda s: (s, None, None),
    "into_the_sun": lambda s: (s, None, into_the_sun(s)),
    "inside_a_cloud": lambda s: (s, None, inside_a_cloud(s)),
    "sunset": lambda s: (s, 18.6, None),
    "midnight": lambda s: (s, 0.0, None),
    "empty_scene": lambda s: (Scene(camera=s.camera), 15.5, None),
    # the pictures of before the clouds' shadows (their goldens those of then): the switch turns them off whole
    "default_view_no_cloud_shadows": lambda s: (s, None, None),
    "sunset_no_cloud_shadows": lambda s: (s, 18.6, None),
    # the picture of before the light shafts (its golden that of then)
    "default_view_no_light_shafts": lambda s: (s, None, None),
}
#: the views drawn with other settings than FULL_3D's
SETTINGS = {name: dataclasses.replace(FULL_3D, cloud_shadows=False) for name in VIEWS if "no_cloud_shadows" in name}
SETTINGS["default_view_no_light_shafts"] = dataclasses.replace(FULL_3D, light_shafts=False)


@pytest.mark.parametrize("name", VIEWS)
def test_render_matches_golden(name, renderer, valley, request):
    scene, hours, camera = VIEWS[name](valley)
    image, _ = renderer.render(scene, time_of_day=hours, camera=camera, settings=SETTINGS.get(name, FULL_3D))
    check_golden(image, name, request)


def test_comparison_catches_a_planted_defect(valley, renderer):
    image, _ = renderer.render(valley, settings=FULL_3D)
    damaged = image.copy()
    damaged[50:60, 70:80] = 255 - damaged[50:60, 70:80]
    difference = compare(image, damaged)
    assert not difference.within(MIN_PSNR_DB, MAX_ABS)
    spot = diff_image(image, damaged)[..., 0]
    assert spot[50:60, 70:80].min() > 0 and spot.sum() == spot[50:60, 70:80].sum()
