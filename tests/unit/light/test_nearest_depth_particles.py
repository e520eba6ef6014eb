"""The particles whose nearest depth cuts the light shafts' march
(`cloudcore.light.light_shafts.nearest_depth_particles`): all of a near unit's, an even share of a far one's."""

import numpy as np

from cloudcore.light.light_shafts import NEAREST_DEPTH_COVERS, nearest_depth_particles

EYE = np.zeros(3)
#: a march of 60 rows over 60 degrees
PIXELS_PER_RADIAN = 60.0 / np.radians(60.0)
CORE = 0.5


def test_a_near_units_clouds_give_every_particle_and_an_empty_cloud_none():
    starts = np.array([0, 5, 5, 12, 20])  # cloud 1 has no particles
    centres, radii, squares = [[0, 0, -500.0], [0, 0, -800.0]], [300.0, 300.0], [30.0**2, 30.0**2]
    chosen = nearest_depth_particles([(3, 1), (0,)], starts, centres, radii, squares, CORE, EYE, PIXELS_PER_RADIAN)
    assert chosen.tolist() == list(range(12, 20)) + list(range(0, 5))
    assert chosen.dtype == np.int32


def test_a_far_unit_gives_as_many_points_as_cover_its_disc_evenly_through_its_clouds():
    starts = np.array([0, 3000, 6000])
    centre, radius = np.array([[0.0, 0.0, -20000.0]]), np.array([400.0])
    chosen = nearest_depth_particles([(0, 1)], starts, centre, radius, [40.0**2], CORE, EYE, PIXELS_PER_RADIAN)
    disc = PIXELS_PER_RADIAN * np.arctan2(400.0, 19600.0)
    # each particle's core under a march pixel: a point covers one
    wanted = NEAREST_DEPTH_COVERS * np.pi * disc**2
    assert wanted <= len(chosen) <= 2.0 * wanted + 2  # every k-th, k the whole share: at most twice the budget
    stride = np.diff(chosen[chosen < 3000])
    assert len(set(stride.tolist())) == 1 and stride[0] > 1  # even steps through the first cloud's order
    assert chosen[0] == 0 and (chosen >= 3000).any()  # both clouds, each from its first particle
    # 3 km away, particles whose cores are wider need fewer to cover the same disc
    near = np.array([[0.0, 0.0, -3000.0]])
    narrow = nearest_depth_particles([(0, 1)], starts, near, radius, [40.0**2], CORE, EYE, PIXELS_PER_RADIAN)
    wide = nearest_depth_particles([(0, 1)], starts, near, radius, [400.0**2], CORE, EYE, PIXELS_PER_RADIAN)
    assert len(wide) < 0.1 * len(narrow)


def test_nothing_drawn_gives_nothing():
    none = np.zeros(0)
    assert len(nearest_depth_particles([], np.array([0, 4]), np.zeros((0, 3)), none, none, CORE, EYE, 1.0)) == 0
    one = np.ones(1)
    assert len(nearest_depth_particles([()], np.array([0, 4]), np.zeros((1, 3)), one, one, CORE, EYE, 1.0)) == 0
