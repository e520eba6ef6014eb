"""The one dither at the 8-bit output: no banding in dark gradients, and the editor's shader agrees with it."""

import numpy as np
import pytest

from cloudcore.maths import colour
from cloudcore.maths.colour import dither_thresholds, linear_to_srgb8, srgb_encode
from cloudcore.model.settings import FULL_3D
from cloudcore.scenes.files import load_scene
from tests.conftest import VALLEY


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)


def test_a_dark_gradient_keeps_its_slope_in_every_4x4_block_instead_of_banding():
    # a night sky's gradient: four sRGB levels (10 to 14) across 256 pixels
    levels = np.linspace(10.0, 14.0, 256)
    linear = np.broadcast_to(srgb_decode(levels / 255.0)[None, :, None], (64, 256, 3))
    out = linear_to_srgb8(linear).astype(np.float64)
    block_means = out.reshape(16, 4, 64, 4, 3).mean(axis=(1, 3))
    exact = levels.reshape(64, 4).mean(axis=1)
    assert np.max(np.abs(block_means - exact[None, :, None])) <= 1.0 / 16.0 + 1e-9
    # rounding alone gives five flat bands, each block up to half a level off
    rounded = np.rint(srgb_encode(linear) * 255.0)
    assert len(np.unique(rounded)) == 5
    assert np.max(np.abs(rounded.reshape(16, 4, 64, 4, 3).mean(axis=(1, 3)) - exact[None, :, None])) > 0.4


def test_a_colour_on_a_level_and_the_ends_of_the_range_stay_exact():
    for level in (0, 1, 128, 254, 255):
        linear = np.full((8, 8, 3), srgb_decode(np.float64(level) / 255.0))
        assert np.all(linear_to_srgb8(linear) == level)
    assert np.all(linear_to_srgb8(np.full((4, 4, 3), np.nan)) == 0)
    assert np.all(linear_to_srgb8(np.full((4, 4, 3), 7.0)) == 255)


def test_the_thresholds_are_every_sixteenth_once_per_block_counted_from_the_bottom_row():
    thresholds = dither_thresholds(6, 8)
    assert sorted(thresholds[2:6, 0:4].ravel() * 16 - 0.5) == list(range(16))
    assert thresholds[5, 0] == 0.5 / 16.0  # the bottom-left pixel is gl_FragCoord (0, 0): Bayer entry 0


@pytest.mark.parametrize("at_once", [1, 7 * 13, 10**9])  # a row a band, 7 rows (bands across the pattern), all
def test_converted_in_bands_every_pixel_is_what_the_whole_frame_at_once_gives(monkeypatch, at_once):
    linear = np.random.default_rng(3).uniform(-0.1, 1.1, (30, 13, 3))
    encoded = srgb_encode(linear) * 255.0 + dither_thresholds(30, 13)[:, :, None]
    whole = np.clip(np.floor(encoded), 0, 255).astype(np.uint8)
    monkeypatch.setattr(colour, "CONVERTED_AT_ONCE", at_once)
    np.testing.assert_array_equal(linear_to_srgb8(linear), whole)
    np.testing.assert_array_equal(linear_to_srgb8(linear[..., 0]), whole[..., 0])


def test_the_editor_s_present_shader_dithers_as_the_read_back_does(renderer):
    image, _ = renderer.render(load_scene(VALLEY), settings=FULL_3D)
    renderer.display_texture()
    shown = renderer.read_display()
    difference = np.abs(shown.astype(int) - image.astype(int))
    # float32 on the GPU against float64 here: a value a hair from a threshold may round the other way
    assert difference.max() <= 1 and np.mean(difference > 0) < 0.01
