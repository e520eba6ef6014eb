"""The particles whose nearest depth cuts the light shafts' march
(`cloudcore.light.light_shafts.cloud_particle_ranges`): each drawn cloud's run of the buffer, in one multi-draw."""

import numpy as np

from cloudcore.light.light_shafts import cloud_particle_ranges


def test_each_cloud_drawn_is_its_run_of_the_buffer_and_an_empty_one_none():
    starts = np.array([0, 5, 5, 12, 20])  # cloud 1 has no particles
    firsts, counts = cloud_particle_ranges([3, 1, 0], starts)
    assert firsts.tolist() == [12, 0] and counts.tolist() == [8, 5]
    assert firsts.dtype == np.int32 and counts.dtype == np.int32


def test_no_cloud_drawn_draws_nothing():
    firsts, counts = cloud_particle_ranges([], np.array([0, 4]))
    assert len(firsts) == 0 and len(counts) == 0
