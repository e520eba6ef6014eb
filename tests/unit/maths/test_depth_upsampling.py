"""The reduced cloud pass's size, the depth it tests against and its depth-aware upsampling (numpy twins of the
shaders: `cloudcore.maths.depth_upsampling`), on a synthetic depth step."""

import numpy as np
import pytest

from cloudcore.maths.depth_upsampling import block_nearest_depth, reduced_size, upsample
from cloudcore.world.camera import FAR_PLANE_M, NEAR_PLANE_M

#: window depths of a surface 500 m away and of the sky
NEAR_DEPTH = (1.0 - NEAR_PLANE_M / 500.0) * FAR_PLANE_M / (FAR_PLANE_M - NEAR_PLANE_M)
SKY_DEPTH = 1.0
CLOUD = np.array([0.6, 0.6, 0.65, 0.8])  # premultiplied: a cloud 2 km away, in front of the sky alone


def step_scene(width: int, height: int, edge: int, size):
    """(the screen's depth: the surface left of column `edge`, sky right of it; the reduced pass's depth and colour
    as the GL draws them: the cloud wherever its block's nearest depth is the sky's)."""
    depth = np.full((height, width), SKY_DEPTH)
    depth[:, :edge] = NEAR_DEPTH
    reduced_depth = block_nearest_depth(depth, size)
    clouds = np.where((reduced_depth == SKY_DEPTH)[..., None], CLOUD, 0.0)
    return depth, reduced_depth, clouds


def test_the_reduced_size_rounds_up_and_keeps_a_pixel():
    assert reduced_size((641, 480), 0.5) == (321, 240)
    assert reduced_size((3, 2), 0.125) == (1, 1)
    assert reduced_size((640, 480), 1.0) == (640, 480)


def test_each_texel_tests_against_the_nearest_depth_of_its_block():
    rng = np.random.default_rng(3)
    depth = rng.uniform(size=(13, 22))
    size = (6, 4)  # blocks of 3 or 4 pixels, unequal
    nearest = block_nearest_depth(depth, size)
    starts_x, starts_y = [0, 4, 8, 11, 15, 19, 22], [0, 4, 7, 10, 13]  # ceil(i * pixels / texels)
    for j in range(size[1]):
        for i in range(size[0]):
            block = depth[starts_y[j] : starts_y[j + 1], starts_x[i] : starts_x[i + 1]]
            assert nearest[j, i] == block.min()


@pytest.mark.parametrize("scale", [0.5, 0.25])
@pytest.mark.parametrize("edge", [13, 16, 18])  # across a block and on its boundary
def test_the_upsampling_keeps_a_depth_step(scale, edge):
    width, height = 40, 8
    size = reduced_size((width, height), scale)
    depth, reduced_depth, clouds = step_scene(width, height, edge, size)
    upsampled = upsample(clouds, reduced_depth, depth, NEAR_PLANE_M, FAR_PLANE_M)
    # no cloud over the surface in front of it (no halo), the whole cloud over the sky up to the edge (no gap)
    np.testing.assert_array_equal(upsampled[:, :edge], 0.0)
    np.testing.assert_allclose(upsampled[:, edge:], np.broadcast_to(CLOUD, upsampled[:, edge:].shape), atol=1e-12)


def test_a_plain_bilinear_upsampling_would_leave_a_gap_along_the_edge():
    """The step above is a real test: without the depth weights the sky beside the edge loses its cloud."""
    width, height, edge = 40, 8, 13
    size = reduced_size((width, height), 0.25)
    depth, reduced_depth, clouds = step_scene(width, height, edge, size)
    flat = np.zeros_like(reduced_depth)  # one depth everywhere: bilinear weights alone
    upsampled = upsample(clouds, flat, np.zeros_like(depth), NEAR_PLANE_M, FAR_PLANE_M)
    assert upsampled[:, edge:, 3].min() < CLOUD[3] - 0.1


def test_on_one_surface_the_upsampling_is_bilinear():
    width, height = 16, 8
    size = reduced_size((width, height), 0.25)
    depth = np.full((height, width), NEAR_DEPTH)
    ramp = np.linspace(0.0, 1.0, size[0])
    clouds = np.broadcast_to(ramp[None, :, None], (size[1], size[0], 4)).copy()
    upsampled = upsample(clouds, block_nearest_depth(depth, size), depth, NEAR_PLANE_M, FAR_PLANE_M)
    # pixel x's centre lies at (x + 0.5) / 4 - 0.5 texels, clamped to the edge texels
    expected = np.interp((np.arange(width) + 0.5) / 4 - 0.5, np.arange(size[0]), ramp)
    np.testing.assert_allclose(upsampled[0, :, 0], expected, atol=1e-12)
