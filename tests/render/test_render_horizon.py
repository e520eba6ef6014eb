"""The default scene's ground reaches the horizon: looking level from the valley, the rays just under the horizon
meet the terrain; the patch alone leaves them to the planet's ground drawn past its edge
(`cloudcore.light.far_ground`), which takes its depth as the terrain does."""

import dataclasses

import numpy as np
import pytest

from cloudcore.model.scene import Camera
from cloudcore.scenes.files import load_scene
from tests.conftest import RENDER_HEIGHT, VALLEY

pytestmark = pytest.mark.gl


def ground_rows_under_the_horizon(renderer, terrain) -> float:
    """The share of the pixels 3 to 6 degrees under the horizontal (the ground 18 to 36 km away) that the
    ground covers (the terrain's or the planet's past it: a depth short of the far plane), looking level down the
    valley from 1.9 km (above its hills: only the far ground is seen)."""
    scene = load_scene(VALLEY)
    eye = (0.0, 1900.0, 5000.0)
    camera = Camera(eye, (0.0, 1900.0, -5000.0), 40.0)
    scene = dataclasses.replace(scene, camera=camera, clouds=(), objects=(), terrain=terrain)
    renderer.render(scene, read_back=False)
    depth = renderer.context.read_depth()
    # rows of the angles below the horizontal: the middle row looks level
    below_deg = (np.arange(RENDER_HEIGHT) + 0.5 - RENDER_HEIGHT / 2) / RENDER_HEIGHT * 40.0
    rows = (below_deg > 3.0) & (below_deg < 6.0)
    return float((depth[rows] < 1.0).mean())


def test_the_ground_reaches_the_horizon(renderer):
    valley = load_scene(VALLEY).terrain
    assert valley.reach >= 30_000.0
    assert ground_rows_under_the_horizon(renderer, valley) == 1.0
    patch = dataclasses.replace(valley, reach=0.0)
    assert ground_rows_under_the_horizon(renderer, patch) == 1.0
