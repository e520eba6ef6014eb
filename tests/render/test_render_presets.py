"""Golden images of every cloud preset (Wang's cloud types, atlas sprites) under noon and sunset light,
shaded by Harris's scattering and by Wang's artist model, at 160x120 (tolerance and the command that
regenerates them: tests/goldens.py)."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.artist.cloudgen import PRESETS, preset_cloud
from cloudcore.model.scene import Camera, Lighting, Scene
from cloudcore.model.settings import FULL_3D
from tests.goldens import check_golden

HOURS = {"noon": 12.0, "sunset": 18.6}
BASE = np.array([0.0, 1500.0, 0.0])


def preset_scene(preset: str, model: str, hour: float) -> Scene:
    """The preset alone in the sky, seen from below its base at 20 degrees, framed whole."""
    cloud = preset_cloud(preset, preset, BASE, seed=3)
    if model == "harris":
        cloud = dataclasses.replace(cloud, artist=None)
    width, height, depth = PRESETS[preset].size
    target = BASE + [0.0, 0.5 * height, 0.0]
    distance = 0.75 * max(width, height, depth) / math.tan(math.radians(30.0))
    elevation = math.radians(-20.0)
    eye = target + distance * np.array([0.0, math.sin(elevation), math.cos(elevation)])
    return Scene(camera=Camera(tuple(eye), tuple(target), 60.0), lighting=Lighting(hour), clouds=(cloud,))


@pytest.mark.parametrize("hour_name", HOURS)
@pytest.mark.parametrize("model", ["harris", "artist"])
@pytest.mark.parametrize("preset", PRESETS)
def test_preset_matches_golden(preset, model, hour_name, renderer, request):
    image, stats = renderer.render(preset_scene(preset, model, HOURS[hour_name]), settings=FULL_3D)
    assert stats.particles_drawn > 0
    check_golden(image, f"preset_{preset}_{model}_{hour_name}", request)


def test_the_two_shading_models_differ_and_both_warm_at_sunset(renderer):
    """The artist model is not Harris's under another name, and both follow the hour (on the cloud's
    pixels: those that differ from the empty sky)."""

    def render(model, hour, clouds=True):
        scene = preset_scene("cumulus_congestus", model, hour)
        scene = scene if clouds else dataclasses.replace(scene, clouds=())
        return renderer.render(scene, settings=FULL_3D)[0].astype(float)

    for model in ("harris", "artist"):
        ratios = []
        for hour in HOURS.values():
            image = render(model, hour)
            cloud = np.abs(image - render(model, hour, clouds=False)).max(axis=2) > 8
            assert cloud.sum() > 500, (model, hour)
            red, blue = image[cloud][:, 0].mean(), image[cloud][:, 2].mean()
            ratios.append(red / blue)
        assert ratios[1] > ratios[0] * 1.1, (model, ratios)
    assert np.abs(render("harris", 12.0) - render("artist", 12.0)).max() > 30
