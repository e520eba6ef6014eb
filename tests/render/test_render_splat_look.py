"""The splats' look per pixel (`cloudcore.light.splat_look`): per-pixel shading against its numpy reference, and the
detail noise off by default, byte for byte.

One particle seen face-on is drawn into a cleared float target, once per particle and once per pixel: through its
centre both give the particle's colour and opacity; off the centre the opacity per pixel is the chord's
(`chord_opacity`) and the colour over the opacity the reference's sun light factor (`sun_light_factor`).
"""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.splat_look import SplatLook, chord_opacity, sun_light_factor
from cloudcore.model.scene import Camera, Cloud, Light, Shading
from cloudcore.model.settings import RenderSettings
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.world.camera import projection_matrix, view_matrix

WIDTH, HEIGHT = 161, 121  # odd: a pixel's centre on the particle's
CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 60.0)
RADIUS, DISTANCE = 30.0, 100.0
SUN = np.array([0.6, 0.0, 0.8])  # from the right and behind the eye: the particle's right is lit
AMBIENT = (0.02, 0.03, 0.05)


def draw(look: SplatLook, optical_depth: float, albedo: float) -> tuple[np.ndarray, ParticleBuffer]:
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.particles.batch import splat_batch

    cloud = Cloud("one", np.array([[0.0, 0.0, -DISTANCE, RADIUS]]), optical_depth=optical_depth, albedo=albedo)
    particles = ParticleBuffer((cloud,), Shading(albedo=albedo), (Light(tuple(SUN), (1.0, 1.0, 1.0), 1.0),), AMBIENT)
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, WIDTH / HEIGHT)
    splats, target = SplatPass(), TextureTarget(WIDTH, HEIGHT)
    try:
        splats.look = look
        target.bind_cleared()
        splats.draw(splat_batch(particles, [0], CAMERA.position), view, projection, depth_test=False)
        return target.read(), particles
    finally:
        target.close()
        splats.close()


def pixel_rays() -> np.ndarray:
    """(HEIGHT, WIDTH, 3): each pixel's unit ray from the eye, top row first."""
    half_height = np.tan(np.radians(CAMERA.fov_y_deg / 2))
    x = ((np.arange(WIDTH) + 0.5) / WIDTH * 2 - 1) * half_height * WIDTH / HEIGHT
    y = (1 - (np.arange(HEIGHT) + 0.5) / HEIGHT * 2) * half_height
    rays = np.stack(np.broadcast_arrays(x[None, :], y[:, None], -np.ones((1, 1))), axis=-1)
    return rays / np.linalg.norm(rays, axis=-1, keepdims=True)


@pytest.mark.parametrize("optical_depth, albedo", [(0.7, 0.9), (8.0, 0.99)])
def test_per_pixel_is_the_particle_through_its_centre_and_the_chord_elsewhere(renderer, optical_depth, albedo):
    renderer.context.make_current()
    per_particle, particles = draw(SplatLook(), optical_depth, albedo)
    per_pixel, _ = draw(SplatLook(per_pixel=True), optical_depth, albedo)
    row, column = HEIGHT // 2, WIDTH // 2
    np.testing.assert_allclose(per_pixel[row, column], per_particle[row, column], rtol=2e-3, atol=1e-5)
    np.testing.assert_allclose(per_particle[row, column, 3], particles.alpha[0], rtol=1e-3)

    centre = np.array([0.0, 0.0, -DISTANCE])
    rays = pixel_rays()
    middles = (rays * (rays @ centre)[..., None] - centre) / RADIUS  # each ray's chord's middle, in radii
    b2 = np.sum(middles * middles, axis=-1)
    inside = b2 < 0.81  # the quad covers the sphere's silhouette there
    expected_alpha = chord_opacity(particles.alpha[0], b2)
    np.testing.assert_allclose(per_pixel[..., 3][inside], expected_alpha[inside], atol=2e-3)
    # per pixel is more opaque off the centre than the kernel's profile: the chord's depth, not its opacity, falls
    assert np.all(per_pixel[..., 3][inside] >= per_particle[..., 3][inside] - 1e-3)

    # the colour over the opacity: the ambient light, plus the sun's part times the light inside the particle
    factor = sun_light_factor(middles, SUN, particles.inner_light_depth[0])
    centre_colour = per_particle[row, column, :3] / per_particle[row, column, 3]
    ambient = AMBIENT[0] * particles.ambient_weight[0]
    expected_red = ambient + (centre_colour[0] - ambient) * factor
    lit = inside & (per_pixel[..., 3] > 0.05)
    np.testing.assert_allclose(per_pixel[..., 0][lit] / per_pixel[..., 3][lit], expected_red[lit], rtol=0.02)
    right, left = per_pixel[row, column + 20], per_pixel[row, column - 20]
    # lit from the right; near the rim the light crosses less of the particle on either side than at its centre
    assert right[0] / right[3] > left[0] / left[3] > centre_colour[0]


def test_the_detail_noise_varies_the_opacity_per_pixel_and_stays_on_the_particle(renderer):
    renderer.context.make_current()
    plain, _ = draw(SplatLook(), 1.5, 0.9)
    noisy, _ = draw(SplatLook(detail_noise=1.0, detail_noise_scale_m=8.0), 1.5, 0.9)
    ratio = noisy[..., 3][plain[..., 3] > 0.05] / plain[..., 3][plain[..., 3] > 0.05]
    assert ratio.min() < 0.8 and ratio.max() > 1.2  # features of 8 m across a particle of 30
    assert np.all(np.isfinite(noisy)) and noisy.min() >= 0.0
    again, _ = draw(SplatLook(detail_noise=1.0, detail_noise_scale_m=8.0), 1.5, 0.9)
    np.testing.assert_array_equal(again, noisy)


def test_the_look_off_is_todays_picture_byte_for_byte_and_on_it_is_not(renderer, small_scene):
    scene = dataclasses.replace(small_scene, terrain=None, objects=())
    today, _ = renderer.render(scene, settings=RenderSettings(mode="full"))
    scaled, _ = renderer.render(scene, settings=RenderSettings(mode="full", detail_noise_scale_m=77.0))
    np.testing.assert_array_equal(scaled, today)
    noisy, _ = renderer.render(scene, settings=RenderSettings(mode="full", detail_noise=0.8))
    per_pixel, _ = renderer.render(scene, settings=RenderSettings(mode="full", particle_shading="per_pixel"))
    assert np.any(noisy != today) and np.any(per_pixel != today)
    again, _ = renderer.render(scene, settings=RenderSettings(mode="full"))
    np.testing.assert_array_equal(again, today)


def test_impostors_are_made_again_when_the_look_changes(renderer, small_scene):
    """The look is in every cloud's key: an impostor made per particle is not shown per pixel."""
    scene = dataclasses.replace(small_scene, terrain=None, objects=())
    impostors = RenderSettings(mode="impostor")
    renderer.render(scene, settings=impostors)
    _, stats = renderer.render(scene, settings=dataclasses.replace(impostors, particle_shading="per_pixel"))
    assert stats.plan.impostors_regenerated > 0
    _, stats = renderer.render(scene, settings=dataclasses.replace(impostors, particle_shading="per_pixel"))
    assert stats.plan.impostors_regenerated == 0
