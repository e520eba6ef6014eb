"""Wang's cloud block overdraw (2004 section 6.3): sprite areas per ground block over the block's area."""

import math

import numpy as np
import pytest

from cloudcore.stats.overdraw import WANG_BLOCK_SIZE_M, cloud_block_overdraw, cloud_block_overdraw_statistics


def test_a_hand_computed_case():
    # blocks of 1 km: two sprites in block (0, 0), one in (-1, 2), one on the edge x = 1000 (block (1, 0));
    # heights (y) do not matter
    centres = np.array([[500.0, 800.0, 500.0], [900.0, 5000.0, 10.0], [-1.0, 0.0, 2500.0], [1000.0, 1.0, 999.0]])
    radii = np.array([100.0, 200.0, 300.0, 50.0])
    blocks, overdraw = cloud_block_overdraw(centres, radii, block_size=1000.0)
    np.testing.assert_array_equal(blocks, [[-1.0, 2.0], [0.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(overdraw, [math.pi * 0.09, math.pi * (0.01 + 0.04), math.pi * 0.0025], rtol=1e-15)
    stats = cloud_block_overdraw_statistics(overdraw)
    assert stats["blocks"] == 3
    assert stats["block_overdraw_max"] == pytest.approx(math.pi * 0.09, rel=1e-15)
    assert stats["block_overdraw_mean"] == pytest.approx(math.pi * (0.09 + 0.05 + 0.0025) / 3, rel=1e-15)


def test_an_overcast_layer_reaches_wangs_overcast_figure():
    """Sprites of radius r spaced 0.8 r apart in a grid over a block: n pi r^2 / s^2, about 4.9 (Wang: 475%)."""
    spacing, radius = 80.0, 100.0
    grid = np.arange(spacing / 2, WANG_BLOCK_SIZE_M, spacing)
    x, z = np.meshgrid(grid, grid)
    centres = np.column_stack([x.ravel(), np.full(x.size, 1500.0), z.ravel()])
    blocks, overdraw = cloud_block_overdraw(centres, np.full(len(centres), radius))
    np.testing.assert_array_equal(blocks, [[0.0, 0.0]])
    assert overdraw[0] == pytest.approx(math.pi * radius**2 / spacing**2, rel=1e-12)


def test_no_particles_give_no_blocks():
    blocks, overdraw = cloud_block_overdraw(np.zeros((0, 3)), np.zeros(0), 100.0)
    assert blocks.shape == (0, 2) and overdraw.shape == (0,) and overdraw.dtype == np.float64
    assert cloud_block_overdraw_statistics(overdraw) == {
        "block_overdraw_max": 0.0,
        "block_overdraw_mean": 0.0,
        "blocks": 0,
    }


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6, 1e150])
def test_the_ratio_does_not_depend_on_the_unit_and_stays_finite(scale):
    centres = np.array([[10.0, 0.0, 10.0], [30.0, 0.0, 70.0], [-50.0, 0.0, 10.0]])
    radii = np.array([5.0, 10.0, 20.0])
    blocks, overdraw = cloud_block_overdraw(centres * scale, radii * scale, 100.0 * scale)
    np.testing.assert_array_equal(blocks, [[-1.0, 0.0], [0.0, 0.0]])
    np.testing.assert_allclose(overdraw, [math.pi * 0.04, math.pi * 0.0125], rtol=1e-12)


@pytest.mark.parametrize("block_size", [0.0, -1.0, math.nan, math.inf])
def test_bad_block_sizes_are_refused(block_size):
    with pytest.raises(ValueError, match="block_size"):
        cloud_block_overdraw(np.zeros((1, 3)), np.ones(1), block_size)


def test_centres_and_radii_must_match():
    with pytest.raises(ValueError, match="radii"):
        cloud_block_overdraw(np.zeros((2, 3)), np.ones(3), 10.0)
