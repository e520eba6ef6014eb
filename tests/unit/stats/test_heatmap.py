"""The overdraw heat map's colours and scale."""

import numpy as np
import pytest

from cloudcore.stats.heatmap import RAMP, heat_image, legend_top, ramp_colours


def test_the_ramp_runs_from_near_black_to_pale_yellow_always_getting_lighter():
    colours = ramp_colours(np.linspace(0.0, 1.0, 257)).astype(float)
    np.testing.assert_array_equal(colours[0], np.rint(RAMP[0] * 255))
    np.testing.assert_array_equal(colours[-1], np.rint(RAMP[-1] * 255))
    luma = colours @ [0.2126, 0.7152, 0.0722]  # lightness rises with the count, so grey prints read right too
    assert np.all(np.diff(luma) >= -1.0) and luma[-1] - luma[0] > 200
    np.testing.assert_array_equal(ramp_colours([-3.0, np.nan, 7.0]), ramp_colours([0.0, 0.0, 1.0]))


def test_counts_are_coloured_on_a_scale_up_to_the_legend_top():
    counts = np.array([[0.0, 2.0], [4.0, 6.3]])
    image, top = heat_image(counts)
    assert top == legend_top(counts) == 7.0 and image.shape == (2, 2, 4) and image.dtype == np.uint8
    np.testing.assert_array_equal(image[..., 3], 255)
    np.testing.assert_array_equal(image[..., :3], ramp_colours(counts / 7.0))
    assert legend_top(np.zeros((3, 3))) == 1.0  # an empty sky still has a scale
    fixed, top = heat_image(counts, top=2.0)
    np.testing.assert_array_equal(fixed[1, 1, :3], np.rint(RAMP[-1] * 255))  # beyond the top: the top colour
    with pytest.raises(ValueError, match="finite and > 0"):
        heat_image(counts, top=0.0)


def test_an_image_texture_holds_the_uploaded_image_row_for_row(renderer):
    from OpenGL import GL

    from cloudcore.gl.image_texture import ImageTexture

    def stored(texture_id: int, shape) -> np.ndarray:
        GL.glBindTexture(GL.GL_TEXTURE_2D, texture_id)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        return np.frombuffer(data, dtype=np.uint8).reshape(*shape, 4)

    renderer.context.make_current()
    texture = ImageTexture()
    try:
        first, _ = heat_image(np.arange(15.0).reshape(3, 5))
        np.testing.assert_array_equal(stored(texture.upload(first), (3, 5)), first)
        again = first[::-1].copy()  # same size: replaced in place
        np.testing.assert_array_equal(stored(texture.upload(again), (3, 5)), again)
        resized, _ = heat_image(np.ones((4, 2)))
        np.testing.assert_array_equal(stored(texture.upload(resized), (4, 2)), resized)
        with pytest.raises(ValueError, match="RGBA8"):
            texture.upload(first[..., :3])
    finally:
        texture.close()
