import numpy as np
import pytest

from cloudcore.paths import sample

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
