"""The splat vertex shader colours particles as `ParticleBuffer.seen_from` does (the numpy reference).

Particles far apart on screen are drawn into a cleared float target; at each
particle's centre pixel the kernel is nearly 1, so the pixel holds the
particle's premultiplied colour and opacity.  Colour over opacity removes
the kernel altogether and must match the reference closely.
"""

import numpy as np
import pytest

from cloudcore.maths.splat_kernel import splat_kernel
from cloudcore.model.cloud_records import Formation
from cloudcore.model.scene import Camera, Cloud, Light, Shading
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.world.camera import projection_matrix, view_matrix

WIDTH, HEIGHT = 160, 120
CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 60.0)
LIGHTS = (
    Light((0.0, 0.0, 1.0), (1.0, 0.9, 0.8), 1.2),  # behind the eye: back scattering
    Light((0.0, 0.6, -0.8), (0.9, 0.95, 1.0), 0.8),  # ahead: forward scattering
    Light((1.0, 0.0, 0.0), (0.3, 0.4, 0.9), 0.5),
)
AMBIENT = (0.05, 0.06, 0.09)


def particle_grid(z: float) -> np.ndarray:
    xs, ys = np.meshgrid(np.linspace(-40.0, 40.0, 6), np.linspace(-24.0, 24.0, 4))
    return np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, z), np.full(xs.size, 6.0)])


@pytest.mark.parametrize(
    "phase, g, eye_pass, light_pass",
    [
        ("rayleigh", 0.0, "harris", "harris"),
        ("henyey-greenstein", 0.8, "harris", "harris"),
        ("cornette-shanks", -0.5, "harris", "harris"),
        ("rayleigh", 0.0, "saturated", "harris"),
        ("rayleigh", 0.0, "yusov", "harris"),
        # the light a lit face sends back, a second light column scattered with the phase function's mean
        ("rayleigh", 0.0, "saturated", "octaves-lit-face"),
        ("henyey-greenstein", 0.8, "saturated", "octaves-lit-face"),
        ("rayleigh", 0.0, "yusov", "octaves-lit-face"),
    ],
)
def test_the_shader_colours_particles_as_the_reference_does(renderer, phase, g, eye_pass, light_pass):
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.particles.batch import splat_batch

    clouds = (
        Cloud("steady", particle_grid(-100.0), optical_depth=2.0, color=(1.0, 0.9, 0.8)),
        Cloud(
            "forming",
            particle_grid(-100.0) + [0.0, 0.0, -0.5, 0.0],
            optical_depth=20.0,
            formation=Formation("form", 0.0, 10.0),
        ),
    )
    shading = Shading(albedo=0.85, phase=phase, g=g, eye_pass=eye_pass, light_pass=light_pass)
    particles = ParticleBuffer(clouds, shading, LIGHTS, AMBIENT)
    # the lit face sends light back to the particles with others behind them (the rows along the third light)
    assert (particles.returned is not None and particles.returned.max() > 0.1) == (light_pass != "harris")
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, WIDTH / HEIGHT)
    time_s = 4.0  # the forming cloud's core is in, its edge not yet
    renderer.context.make_current()
    splats, target = SplatPass(), TextureTarget(WIDTH, HEIGHT)
    try:
        for cloud in range(2):
            target.bind_cleared()
            splats.draw(
                splat_batch(particles, [cloud], CAMERA.position, time_s=time_s), view, projection, depth_test=False
            )
            pixels = target.read()
            indices = np.arange(particles.cloud_starts[cloud], particles.cloud_starts[cloud + 1])
            colour, alpha = particles.seen_from(CAMERA.position, indices, time_s=time_s)
            for index, expected_colour, expected_alpha in zip(indices, colour, alpha):
                clip = projection @ view @ np.append(particles.centres[index], 1.0)
                ndc = clip[:2] / clip[3]
                column, row = (ndc[0] + 1) / 2 * WIDTH - 0.5, (1 - ndc[1]) / 2 * HEIGHT - 0.5
                pixel = pixels[int(round(row)), int(round(column))]
                offset_px = np.hypot(column - round(column), row - round(row))
                kernel_floor = float(splat_kernel(offset_px / (6.0 / 100.0 / np.tan(np.radians(30)) * HEIGHT / 2)))
                if expected_alpha == 0.0:
                    assert np.all(pixel == 0.0), f"particle {index} should be invisible, got {pixel}"
                    continue
                assert kernel_floor * expected_alpha * 0.99 <= pixel[3] <= expected_alpha * 1.01, (index, pixel)
                np.testing.assert_allclose(
                    pixel[:3] / pixel[3],
                    expected_colour / expected_alpha,
                    rtol=0.01,
                    atol=2e-4,
                    err_msg=f"particle {index} ({phase}, g={g})",
                )
            if cloud == 1:  # the formation reached the shader: some particles in, some still out
                assert 0 < np.count_nonzero(alpha) < len(alpha)
    finally:
        target.close()
        splats.close()


def test_the_shader_colours_artist_clouds_as_the_reference_does(renderer):
    """Wang's model per corner (`artist_colours`); the quad's centre lies on the diagonal between
    its lower-right and upper-left corners, so it gets their mean."""
    from cloudcore.artist.artist_shading import artist_colours
    from cloudcore.artist.particle_styles import particle_styles
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.model.cloud_records import ArtistShading
    from cloudcore.model.scene import Lighting
    from cloudcore.particles.batch import splat_batch
    from cloudcore.world.sun import sun_direction

    particles_xyzr = np.array([[0.0, -20.0, -100.0, 40.0], [0.0, 20.0, -100.0, 40.0], [30.0, 0.0, -160.0, 40.0]])
    cloud = Cloud("artist", particles_xyzr, artist=ArtistShading(), shading_group_size=1000.0)
    hour = 17.0
    styles = particle_styles((cloud,), Lighting(hour))
    particles = ParticleBuffer((cloud,), Shading(), LIGHTS, AMBIENT, styles=styles)
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, WIDTH / HEIGHT)
    renderer.context.make_current()
    splats, target = SplatPass(), TextureTarget(WIDTH, HEIGHT)
    try:
        target.bind_cleared()
        nearest = splat_batch(particles, [0], CAMERA.position).order[-1:]  # the one drawn last, on top
        batch = splat_batch(particles, [0], CAMERA.position)
        splats.draw(batch, view, projection, depth_test=False)
        pixels = target.read()
    finally:
        target.close()
        splats.close()
    index = int(nearest[0])
    centre, radius = particles_xyzr[index, :3], particles_xyzr[index, 3]
    right, up = view[0, :3], view[1, :3]
    corners = np.array([centre + radius * (right - up), centre + radius * (up - right)])  # lower right, upper left
    group = np.repeat(particles_xyzr[:, :3].mean(axis=0, keepdims=True), 2, axis=0)
    y = particles_xyzr[:, 1]
    expected = artist_colours(cloud.artist, corners, y.min(), y.max(), group, sun_direction(hour), hour).mean(axis=0)
    clip = projection @ view @ np.append(centre, 1.0)
    column, row = (clip[0] / clip[3] + 1) / 2 * WIDTH - 0.5, (1 - clip[1] / clip[3]) / 2 * HEIGHT - 0.5
    pixel = pixels[int(round(row)), int(round(column))]
    np.testing.assert_allclose(pixel[:3] / pixel[3], expected[:3], rtol=0.03, atol=3e-3)
    assert 0.97 * expected[3] <= pixel[3] <= 1.01  # the kernel is nearly 1 at the centre; nothing lies over it


def test_a_sprite_the_eye_stands_in_keeps_its_facing_and_fades_as_the_eye_circles_it(renderer):
    """Wang 3.3: within half its radius a sprite stops turning toward the eye; circling it, the eye
    sees it fade with the angle to its locked facing, gone by 90 degrees (a splat there would
    simply be gone: the near fade)."""
    import dataclasses

    from cloudcore.model.cloud_records import PUFFY, SpriteStyle
    from cloudcore.model.scene import Lighting, Scene
    from cloudcore.model.settings import FULL_3D

    cloud = Cloud("sprite", [[0.0, 0.0, 0.0, 100.0]], sprite=SpriteStyle(rows=(PUFFY,), rotation_deg=(0.0, 0.0)))
    scene = Scene(lighting=Lighting(12.0), clouds=(cloud,))
    angles = np.radians(np.arange(0, 130, 10))
    cameras = [Camera((30.0 * np.sin(angle), 0.0, 30.0 * np.cos(angle)), (0.0, 0.0, 0.0)) for angle in angles]
    # the clear sky seen each way, first: the atmosphere's changes with the azimuth, and a frame without the
    # sprite between two with it would forget its locked facing
    skies = [renderer.render(dataclasses.replace(scene, clouds=()), camera=c, settings=FULL_3D)[0] for c in cameras]

    def visible(camera: Camera, sky: np.ndarray) -> float:
        """Mean brightness the sprite adds, seen from 30 m (0.3 radii) by `camera`, over the clear `sky`."""
        image = renderer.render(scene, camera=camera, settings=FULL_3D)[0]
        return float(np.abs(image.astype(float) - sky.astype(float)).mean())

    seen = [visible(camera, sky) for camera, sky in zip(cameras, skies, strict=True)]
    assert seen[0] > 10.0, seen  # locked at first sight, in full view
    assert all(later <= earlier + 0.5 for earlier, later in zip(seen, seen[1:])), seen
    assert seen[9] < 0.5 and seen[-1] < 0.5, seen  # edge-on at 90 degrees and beyond: gone


def test_splats_left_out_by_the_frustum_change_no_pixel(renderer):
    """A cloud around the eye: most of its splats are behind it or off screen, and leaving them out is exact."""
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.lod.splat_coverage import splats_in_frustum
    from cloudcore.particles.batch import splat_batch
    from cloudcore.world.camera import frustum_planes

    rng = np.random.default_rng(5)
    around = np.column_stack([rng.uniform(-300.0, 300.0, (2000, 3)), rng.uniform(4.0, 40.0, 2000)])
    particles = ParticleBuffer((Cloud("around the eye", around, optical_depth=1.0),), Shading(), LIGHTS, AMBIENT)
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, WIDTH / HEIGHT)
    frustum = frustum_planes(projection @ view)
    renderer.context.make_current()
    splats, target = SplatPass(), TextureTarget(WIDTH, HEIGHT)
    try:
        pictures = []
        for planes in (None, frustum):
            target.bind_cleared()
            batch = splat_batch(particles, [0], CAMERA.position, frustum=planes)
            splats.draw(batch, view, projection, depth_test=False, point_sprites=False)  # quads: bit for bit
            pictures.append((len(batch), target.read()))
    finally:
        splats.close()
        target.close()
    (every, everything), (culled, in_view) = pictures
    assert culled == np.count_nonzero(splats_in_frustum(frustum, around[:, :3], around[:, 3])) < every / 3
    assert np.array_equal(everything, in_view)
