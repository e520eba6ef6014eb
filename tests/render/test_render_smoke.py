"""Smoke test of the headless GL renderer (cloudcore.gl) on the default scene.

Skipped where no EGL context can be made (no libEGL, no Mesa driver).
"""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.sky_background import scene_sky
from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.model.scene import Air, Camera, Lighting
from cloudcore.model.settings import FULL_3D
from cloudcore.scenes.files import load_scene
from cloudcore.world.camera import pixel_rays
from tests.conftest import RENDER_HEIGHT as HEIGHT
from tests.conftest import RENDER_WIDTH as WIDTH
from tests.conftest import VALLEY

STATS_KEYS = {"frame_ms", "world_ms", "cloud_ms", "particles_drawn", "clouds_drawn", "clouds_culled"}


@pytest.fixture(scope="module")
def valley():
    return load_scene(VALLEY)


@pytest.fixture(scope="module")
def afternoon(renderer, valley):
    return renderer.render(valley, time_of_day=15.5, settings=FULL_3D)


def luminance(rgb):
    return rgb.astype(float) @ [0.2126, 0.7152, 0.0722]


def test_frame_is_a_valid_image_with_stats(afternoon, valley):
    rgb, stats = afternoon
    assert rgb.shape == (HEIGHT, WIDTH, 3) and rgb.dtype == np.uint8
    assert rgb.std() > 5  # not a blank frame
    row = stats.as_dict()
    assert STATS_KEYS <= row.keys()
    assert all(np.isfinite(row[key]) and row[key] >= 0 for key in STATS_KEYS)
    assert stats.clouds_drawn + stats.clouds_culled == len(valley.clouds)
    assert 0 < stats.particles_drawn <= valley.particle_count


def test_each_pass_is_timed_on_the_cpu_and_on_the_gpu_within_its_wall_time(afternoon):
    _, stats = afternoon
    passes = {
        "world": (stats.world_ms, stats.world_gpu_ms),
        "impostor updates": (stats.impostor_update_ms, stats.impostor_update_gpu_ms),
        "clouds": (stats.cloud_ms, stats.cloud_gpu_ms),
    }
    # the GPU's time lies inside the pass's share of the frame (a millisecond for the clocks' grain)
    for name, (wall_ms, gpu_ms) in passes.items():
        assert 0.0 <= gpu_ms <= wall_ms + 1.0, (name, wall_ms, gpu_ms)
    assert stats.cloud_gpu_ms > 0.0 and stats.world_gpu_ms > 0.0  # full 3D draws both
    assert 0.0 < stats.cpu_ms


def test_the_frame_time_holds_the_planning_and_the_passes(afternoon):
    _, stats = afternoon
    assert 0.0 < stats.plan_ms <= stats.cpu_ms
    assert stats.frame_ms == pytest.approx(stats.plan_ms + stats.world_ms + stats.impostor_update_ms + stats.cloud_ms)


def test_sky_at_the_top_is_blue(afternoon):
    """The atmosphere's blue, as bright as the model says (its zenith a deeper blue than the gradient's)."""
    r, g, b = afternoon[0][0, WIDTH // 2].astype(int)
    assert b > g > r
    camera = load_scene(VALLEY).camera
    ray = pixel_rays(camera, WIDTH, HEIGHT)[0, WIDTH // 2]
    expected = linear_to_srgb8(scene_sky(Lighting(time_of_day=15.5)).radiance(ray, 1e-3).reshape(1, 1, 3))[0, 0]
    expected = expected.astype(int)
    assert np.abs([r, g, b] - expected).max() <= 2, expected


def test_the_gradient_sky_at_the_top_is_the_pale_blue_of_before(renderer, valley):
    scene = dataclasses.replace(valley, lighting=dataclasses.replace(valley.lighting, air=Air(sky="gradient")))
    r, g, b = renderer.render(scene, time_of_day=15.5, settings=FULL_3D)[0][0, WIDTH // 2].astype(int)
    assert b > g > r and b > 150


def test_clouds_are_brighter_than_the_sky_behind_them(renderer, valley, afternoon):
    clear, _ = renderer.render(dataclasses.replace(valley, clouds=()), time_of_day=15.5, settings=FULL_3D)
    added = luminance(afternoon[0]) - luminance(clear)
    assert (added > 20).mean() > 0.01


def test_midnight_is_dark_blue_not_black_holes(renderer, valley):
    rgb, _ = renderer.render(valley, time_of_day=0.0, settings=FULL_3D)
    mean = rgb.reshape(-1, 3).mean(axis=0)
    assert mean[2] > mean[0] and mean.max() < 80
    assert rgb.max(axis=2).min() > 0  # no pixel lost to NaN or black


def test_depth_of_world_and_clouds_agree_with_pyrender(renderer):
    from cloudcore.gl.pyrender_compat import pyrender
    from cloudcore.world.camera import camera_pose, projection_matrix, view_matrix

    camera = Camera((10.0, 500.0, 300.0), (-200.0, 900.0, -100.0), 45.0)
    ours = projection_matrix(camera.fov_y_deg, WIDTH / HEIGHT)
    theirs = pyrender.PerspectiveCamera(np.radians(45.0), znear=1.0, zfar=1e5).get_projection_matrix(WIDTH, HEIGHT)
    np.testing.assert_allclose(ours, theirs, rtol=1e-12)
    np.testing.assert_allclose(view_matrix(camera) @ camera_pose(camera), np.eye(4), atol=1e-12)


def test_pyrender_bounds_work_under_numpy_2(renderer):
    from cloudcore.gl.pyrender_compat import pyrender

    scene = pyrender.Scene()
    scene.add(pyrender.Mesh([pyrender.Primitive(positions=np.eye(3, dtype=np.float32))]))
    np.testing.assert_allclose(scene.bounds, [[0, 0, 0], [1, 1, 1]])


def test_an_antialiased_world_differs_only_along_the_terrains_edges(renderer, valley):
    # without the clouds' shadows: multisampled, a pixel's depth is one sample's, off the pixel's centre, and the far
    # ground's shadow edges move by it (6.5% of the pixels by over 8 levels at 160x120)
    unshadowed = dataclasses.replace(FULL_3D, cloud_shadows=False)
    plain, _ = renderer.render(valley, time_of_day=15.5, settings=unshadowed)
    smooth, stats = renderer.render(
        valley, time_of_day=15.5, settings=dataclasses.replace(unshadowed, world_antialiasing=True)
    )
    changed = np.abs(smooth.astype(int) - plain.astype(int)).max(axis=2) > 8
    assert 0.0 < changed.mean() < 0.01, changed.mean()  # the ridge line and nothing else
    assert stats.world_ms > 0.0
