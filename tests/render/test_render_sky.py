"""The world pass draws the sky of `cloudcore.light.sky_background`: the atmosphere's table and the sun's disc as the
numpy side reads them (the truth composites that one), and the gradient as before."""

import numpy as np
import pytest

from cloudcore.gl.frame import FrameRenderer
from cloudcore.gl.world import sky_reduction
from cloudcore.light.relighting import PREVIEW_METHOD
from cloudcore.light.sky_background import SUN_DISC_PEAK, scene_sky
from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.measure.imagecompare import compare
from cloudcore.model.scene import Air, Camera, Lighting, Scene
from cloudcore.world.camera import pixel_rays
from cloudcore.world.sun import sun_direction
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH

pytestmark = pytest.mark.gl


def sky_frame(renderer, lighting: Lighting, camera: Camera, method: str = "exact") -> np.ndarray:
    renderer.render(Scene(camera=camera, lighting=lighting), read_back=False, illumination_method=method)
    return renderer.context.read_linear_rgb()


def looking_at_the_sun(hours: float, fov_y_deg: float = 60.0, altitude_m: float = 200.0) -> Camera:
    eye = np.array([0.0, altitude_m, 0.0])
    return Camera(tuple(eye), tuple(eye + 1000.0 * sun_direction(hours)), fov_y_deg)


@pytest.mark.parametrize(
    ("hours", "sky", "method", "altitude_m"),
    [
        (12.0, "physical", "exact", 200.0),
        (18.6, "physical", "exact", 200.0),
        (18.6, "physical", "exact", 6000.0),
        (18.6, "physical", "preview", 200.0),
        (18.6, "gradient", "exact", 200.0),
    ],
)
def test_the_world_pass_draws_the_numpy_sky(renderer, hours, sky, method, altitude_m):
    """Toward the sun at noon (the disc in the middle), at sunset (the disc on the horizon, the ground below it),
    from 6 km up (the sky seen from there); a dragged slider's look (the preview method) draws the coarse table."""
    lighting = Lighting(time_of_day=hours, air=Air(sky=sky))
    camera = looking_at_the_sun(hours, altitude_m=altitude_m)
    drawn = sky_frame(renderer, lighting, camera, method)
    rays = pixel_rays(camera, RENDER_WIDTH, RENDER_HEIGHT)
    background = scene_sky(lighting, preview=method == PREVIEW_METHOD).seen_from(camera.position)
    expected = background.radiance(rays, np.radians(camera.fov_y_deg) / RENDER_HEIGHT)
    # float32 directions and a 16-bit float target (2^-11 relative); the disc's rim turns on within a pixel, so a
    # few pixels on it differ by much: all but those within 1% + 1e-3
    close = np.abs(drawn - expected) <= 0.01 * expected + 1e-3
    assert close.all(axis=-1).mean() > 0.995, f"{np.count_nonzero(~close.all(axis=-1))} pixels differ"
    if sky == "physical":
        assert drawn.max() > 1.0 and drawn.max() <= SUN_DISC_PEAK * 1.001  # the disc is in view, capped


@pytest.mark.parametrize(("yaw_deg", "pitch_deg"), [(6.5, 0.0), (-6.5, 4.2)])
def test_the_sun_s_disc_near_the_screen_s_corner_is_drawn_whole(renderer, yaw_deg, pitch_deg):
    """The disc is drawn in a box around it (`world.sun_box`): near the corner of a wide view, where a pixel spans
    the least angle, every pixel of it is the numpy sky's (a 12 degree view: the disc 4 pixels across)."""
    hours = 9.0
    sun = sun_direction(hours)
    yaw, pitch = np.radians(yaw_deg), np.radians(pitch_deg)
    turned = np.array([sun[0] * np.cos(yaw) - sun[2] * np.sin(yaw), 0.0, sun[0] * np.sin(yaw) + sun[2] * np.cos(yaw)])
    turned = turned / np.linalg.norm(turned) * np.cos(np.arcsin(sun[1]) + pitch)
    turned[1] = np.sin(np.arcsin(sun[1]) + pitch)
    eye = np.array([0.0, 200.0, 0.0])
    camera = Camera(tuple(eye), tuple(eye + 1000.0 * turned), 12.0)
    lighting = Lighting(time_of_day=hours)
    drawn = sky_frame(renderer, lighting, camera)
    expected = (
        scene_sky(lighting)
        .seen_from(camera.position)
        .radiance(pixel_rays(camera, RENDER_WIDTH, RENDER_HEIGHT), np.radians(camera.fov_y_deg) / RENDER_HEIGHT)
    )
    on_disc = expected.max(axis=-1) > 1.0
    assert 20 <= np.count_nonzero(on_disc) < 200  # the disc, in view
    np.testing.assert_allclose(drawn[on_disc], expected[on_disc], rtol=0.02, atol=1e-3)


def test_the_sun_s_disc_is_as_wide_as_the_sun_and_darker_at_its_limb(renderer):
    camera = looking_at_the_sun(12.0, fov_y_deg=2.0)  # 120 pixels across 2 degrees: the disc 32 wide
    drawn = sky_frame(renderer, Lighting(time_of_day=12.0), camera).mean(axis=-1)
    row = drawn[RENDER_HEIGHT // 2]
    on_disc = np.flatnonzero(row > 0.5 * row.max())
    assert 30 <= len(on_disc) <= 34
    assert row[on_disc[2]] < 0.8 * row[RENDER_WIDTH // 2]


def test_a_climbing_eye_sees_the_sky_from_its_altitude(renderer):
    """From 8 km up the zenith is darker and the horizon has sunk (the air at it drawn lower): the sky is the one
    seen from the eye, not from the scene's origin."""
    lighting = Lighting(time_of_day=15.5)
    level = np.array([0.0, 0.0, -1000.0])
    pictures = {
        altitude: sky_frame(renderer, lighting, Camera((0.0, altitude, 0.0), tuple(level + [0.0, altitude, 0.0]), 60.0))
        for altitude in (100.0, 8000.0)
    }
    top = {altitude: float(picture[0].mean()) for altitude, picture in pictures.items()}
    assert top[8000.0] < 0.9 * top[100.0]
    # the brightest row (the air at the horizon) lies at the middle from near the ground, lower from 8 km
    brightest = {altitude: int(np.argmax(picture.mean(axis=(1, 2)))) for altitude, picture in pictures.items()}
    assert brightest[8000.0] > brightest[100.0] + 2


def test_the_sky_seen_from_an_eye_steps_with_the_air_s_volume():
    """An eye within a step of the sky's altitude sees the sky itself; the scene's origin's altitude counts; the
    gradient is the same from everywhere."""
    sky = scene_sky(Lighting(time_of_day=10.0, air=Air(origin_altitude_m=1000.0)))
    assert sky.seen_from((5.0, 40.0, 0.0)) is sky
    high = sky.seen_from((0.0, 1480.0, 0.0))
    assert high.view.altitude_m == 2500.0 and high.origin_altitude_m == 1000.0
    assert high.eye_altitude_m((0.0, 0.0, 0.0)) == 1000.0  # the air between stays measured from the origin
    top = sky.seen_from((0.0, 99_000.0, 0.0)).view
    assert top.altitude_m == 100_000.0  # the air's top: above it, the same table for every eye
    assert sky.seen_from((0.0, 2e5, 0.0)).view is top and sky.seen_from((0.0, 1e12, 0.0)).view is top
    gradient = scene_sky(Lighting(air=Air(sky="gradient")))
    assert gradient.seen_from((0.0, 9000.0, 0.0)) is gradient


@pytest.mark.parametrize("hours", [17.6, 11.0])
def test_the_sky_read_from_its_picture_is_the_sky_a_pixel_within_what_8_bits_show(hours):
    """At 640x480 the physical sky is drawn at a fifth of the resolution a side (`world.sky_reduction`) and read
    bilinearly: toward the low sun (its aureole changes fastest) and at noon, within 57 dB of the numpy sky
    (8-bit sRGB), the disc drawn at the screen's own."""
    width, height = 640, 480
    assert sky_reduction(width) == 5
    lighting = Lighting(time_of_day=hours)
    camera = looking_at_the_sun(hours, fov_y_deg=50.0)
    with FrameRenderer(width, height) as renderer:
        drawn = sky_frame(renderer, lighting, camera)
    expected = (
        scene_sky(lighting)
        .seen_from(camera.position)
        .radiance(pixel_rays(camera, width, height), np.radians(camera.fov_y_deg) / height)
    )
    assert compare(linear_to_srgb8(drawn), linear_to_srgb8(expected)).psnr_db > 57.0  # 60-63 dB measured
