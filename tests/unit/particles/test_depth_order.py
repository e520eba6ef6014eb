"""The linear-time far-to-near sort orders as a stable comparison sort of float32 distances does."""

import numpy as np
import pytest

from cloudcore.particles.depth_order import far_to_near


@pytest.mark.parametrize("seed", range(4))
def test_the_order_is_a_stable_descending_sort_of_float32_distances(seed):
    rng = np.random.default_rng(seed)
    distances = rng.uniform(0.0, 10.0 ** rng.uniform(-6, 7), 5000)
    distances[:300] = distances[300]  # ties keep their input order
    distances[300:400] = 0.0  # the eye at a particle's centre
    expected = np.argsort(-distances.astype(np.float32), kind="stable")
    np.testing.assert_array_equal(far_to_near(distances), expected)


def test_extremes_and_empty_input():
    distances = np.array([0.0, 1e-30, 1e6, np.finfo(np.float32).max, 1.0])
    np.testing.assert_array_equal(far_to_near(distances), [3, 2, 4, 1, 0])
    assert far_to_near(np.zeros(0)).shape == (0,)
