"""The world pass draws the sky of `cloudcore.light.sky_background`: the atmosphere's table and the sun's disc as the
numpy side reads them (the truth composites that one), and the gradient as before."""

import numpy as np
import pytest
from conftest import RENDER_HEIGHT, RENDER_WIDTH

from cloudcore.camera import pixel_rays
from cloudcore.light.relighting import PREVIEW_METHOD
from cloudcore.light.sky_background import SUN_DISC_PEAK, scene_sky
from cloudcore.scene import Air, Camera, Lighting, Scene
from cloudcore.sun import sun_direction

pytestmark = pytest.mark.gl


def sky_frame(renderer, lighting: Lighting, camera: Camera, method: str = "exact") -> np.ndarray:
    renderer.render(Scene(camera=camera, lighting=lighting), read_back=False, illumination_method=method)
    return renderer.context.read_linear_rgb()


def looking_at_the_sun(hours: float, fov_y_deg: float = 60.0) -> Camera:
    eye = np.array([0.0, 200.0, 0.0])
    return Camera(tuple(eye), tuple(eye + 1000.0 * sun_direction(hours)), fov_y_deg)


@pytest.mark.parametrize(
    ("hours", "sky", "method"),
    [
        (12.0, "physical", "exact"),
        (18.6, "physical", "exact"),
        (18.6, "physical", "preview"),
        (18.6, "gradient", "exact"),
    ],
)
def test_the_world_pass_draws_the_numpy_sky(renderer, hours, sky, method):
    """Toward the sun at noon (the disc in the middle), at sunset (the disc on the horizon, the ground below it);
    a dragged slider's look (the preview method) draws the coarse table."""
    lighting = Lighting(time_of_day=hours, air=Air(sky=sky))
    camera = looking_at_the_sun(hours)
    drawn = sky_frame(renderer, lighting, camera, method)
    rays = pixel_rays(camera, RENDER_WIDTH, RENDER_HEIGHT)
    background = scene_sky(lighting, preview=method == PREVIEW_METHOD)
    expected = background.radiance(rays, np.radians(camera.fov_y_deg) / RENDER_HEIGHT)
    # float32 directions and a 16-bit float target (2^-11 relative); the disc's rim turns on within a pixel, so a
    # few pixels on it differ by much: all but those within 1% + 1e-3
    close = np.abs(drawn - expected) <= 0.01 * expected + 1e-3
    assert close.all(axis=-1).mean() > 0.995, f"{np.count_nonzero(~close.all(axis=-1))} pixels differ"
    if sky == "physical":
        assert drawn.max() > 1.0 and drawn.max() <= SUN_DISC_PEAK * 1.001  # the disc is in view, capped


def test_the_sun_s_disc_is_as_wide_as_the_sun_and_darker_at_its_limb(renderer):
    camera = looking_at_the_sun(12.0, fov_y_deg=2.0)  # 120 pixels across 2 degrees: the disc 32 wide
    drawn = sky_frame(renderer, Lighting(time_of_day=12.0), camera).mean(axis=-1)
    row = drawn[RENDER_HEIGHT // 2]
    on_disc = np.flatnonzero(row > 0.5 * row.max())
    assert 30 <= len(on_disc) <= 34
    assert row[on_disc[2]] < 0.8 * row[RENDER_WIDTH // 2]
