import numpy as np
import pytest

from cloudcore.maths.paths import camera_on_path, sample
from cloudcore.model.scene import Camera, CameraPath
from cloudcore.world.camera import camera_pose

KEYS = np.array([[0.0, 0, 0, 0], [1.0, 10, 0, 0], [3.0, 10, 10, 0], [4.0, 0, 10, 5]])


@pytest.mark.parametrize("row", range(4))
def test_path_passes_through_every_key(row):
    np.testing.assert_allclose(sample(KEYS, KEYS[row, 0]), KEYS[row, 1:], atol=1e-12)


def test_time_outside_the_keys_clamps_to_the_ends():
    np.testing.assert_array_equal(sample(KEYS, -5.0), KEYS[0, 1:])
    np.testing.assert_array_equal(sample(KEYS, 50.0), KEYS[-1, 1:])


def test_path_is_continuous_and_smooth():
    times = np.linspace(0, 4, 4001)
    points = np.array([sample(KEYS, t) for t in times])
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    assert steps.max() < 0.05  # no jumps
    velocity = np.diff(points, axis=0) / np.diff(times)[:, None]
    assert np.abs(np.diff(velocity, axis=0)).max() < 0.5  # no kinks at the keys (C1)


@pytest.mark.parametrize("offset", [1e-300, 5e-324])
def test_a_look_at_point_a_denormal_away_still_gives_an_orthonormal_pose(offset):
    """The root of the squares was 0 there: a division by zero."""
    pose = camera_pose(Camera((0.0, 0.0, 0.0), (0.0, 0.0, offset)))
    assert np.allclose(pose[:3, :3].T @ pose[:3, :3], np.eye(3))
    assert np.allclose(pose[:3, 2], (0.0, 0.0, -1.0))  # looking down +z: the back axis is -z


def test_between_keys_that_swap_eye_and_target_the_eye_at_its_target_looks_down_minus_z():
    keys = np.array([[0, 0, 800, 1500, 0, 800, 1400], [1, 0, 800, 1400, 0, 800, 1500]], dtype=float)
    camera = camera_on_path(CameraPath("swap", keys), 0.5, 60.0)
    assert np.array_equal(camera.position, camera.look_at)
    pose = camera_pose(camera)
    assert np.all(np.isfinite(pose)) and np.allclose(pose[:3, 2], (0.0, 0.0, 1.0))
