"""Plain splats drawn as point sprites give the picture quads give (`cloudcore.particles.point_sprites`)."""

import numpy as np
import pytest

from cloudcore.artist.particle_styles import particle_styles
from cloudcore.lod.impostors import impostor_view
from cloudcore.model.scene import Camera, Cloud, Light, Shading
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.particles.point_sprites import draw_runs, plain_splats, point_sprite_mask
from cloudcore.world.camera import projection_matrix, view_matrix

CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 60.0)
LIGHTS = (Light((0.0, 0.6, -0.8), (1.0, 0.95, 0.9), 1.0),)
AMBIENT = (0.05, 0.06, 0.09)
POINT_SIZES_PX = (1.0, 255.0)


def points_fit(*args) -> bool:
    return bool(point_sprite_mask(*args).all())


def rotation_of(view: np.ndarray) -> np.ndarray:
    rotation = np.array(view, dtype=np.float64)
    rotation[:3, 3] = 0.0
    return rotation


def test_splats_inside_the_view_fit_and_a_centre_outside_it_does_not():
    view, projection = rotation_of(view_matrix(CAMERA)), projection_matrix(60.0, 4 / 3)
    ahead = np.array([[0.0, 0.0, -100.0], [30.0, 20.0, -100.0]])
    assert points_fit(ahead, [5.0, 5.0], view, projection, (160, 120), POINT_SIZES_PX)
    # its disc reaches into the view, but GL would discard the whole point
    beside = np.vstack([ahead, [[80.0, 0.0, -100.0]]])  # the view ends at x = 77
    assert not points_fit(beside, [5.0, 5.0, 10.0], view, projection, (160, 120), POINT_SIZES_PX)
    behind = np.vstack([ahead, [[0.0, 0.0, 10.0]]])
    assert not points_fit(behind, [5.0, 5.0, 1.0], view, projection, (160, 120), POINT_SIZES_PX)


def test_a_square_wider_than_the_largest_point_keeps_quads():
    view, projection = rotation_of(view_matrix(CAMERA)), projection_matrix(60.0, 1.0)
    # side in pixels = r * focal * height / depth: 100 px at a height of 100, 1000 px at ten times it
    centre, radius = np.array([[0.0, 0.0, -100.0]]), [100.0 / projection[1, 1]]
    assert points_fit(centre, radius, view, projection, (100, 100), POINT_SIZES_PX)
    assert not points_fit(centre, radius, view, projection, (1000, 1000), POINT_SIZES_PX)


def test_pixels_that_are_not_square_keep_quads():
    view, projection = rotation_of(view_matrix(CAMERA)), projection_matrix(60.0, 4 / 3)
    centre = np.array([[0.0, 0.0, -100.0]])
    assert points_fit(centre, [1.0], view, projection, (160, 120), POINT_SIZES_PX)
    assert not points_fit(centre, [1.0], view, projection, (160, 160), POINT_SIZES_PX)


def test_only_plain_gaussian_splats_with_one_colour_are_plain(small_scene):
    styles = particle_styles(small_scene.clouds, small_scene.lighting)
    plain = plain_splats(styles)
    for index, cloud in enumerate(small_scene.clouds):
        mine = plain[styles.cloud_index == index]
        assert mine.all() == (cloud.sprite is None and cloud.artist is None), cloud.name
        assert mine.all() or not mine.any()
    assert plain.any() and not plain.all()  # the fixture has both kinds


def dense_cloud(rng, count: int) -> np.ndarray:
    centres = rng.normal(size=(count, 3)) * [60.0, 25.0, 60.0] + [0.0, 0.0, -600.0]
    return np.column_stack([centres, rng.uniform(6.0, 30.0, count)])


@pytest.mark.parametrize("counting", [False, True], ids=["colour", "fragment count"])
def test_an_impostor_drawn_with_points_is_the_one_drawn_with_quads(renderer, counting):
    """Through an impostor's off-axis frustum, fitted around the cloud as regenerations are."""
    from OpenGL import GL

    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.particles.batch import splat_batch

    particles_array = dense_cloud(np.random.default_rng(3), 400)
    particles = ParticleBuffer((Cloud("cumulus", particles_array, optical_depth=1.5),), Shading(), LIGHTS, AMBIENT)
    eye = np.array([150.0, 40.0, 0.0])
    centre = particles_array[:, :3].mean(axis=0)
    radius = float(np.max(np.linalg.norm(particles_array[:, :3] - centre, axis=1) + particles_array[:, 3]))
    view = impostor_view(centre, radius, eye)
    renderer.context.make_current()
    size = 96
    splats = SplatPass()
    target = TextureTarget(size, size, GL.GL_R32F if counting else GL.GL_RGBA16F)
    try:
        pictures = []
        for point_sprites in (False, True):
            target.bind_cleared()
            batch = splat_batch(particles, [0], eye)
            as_points = splats.draw(
                batch, view.view, view.projection, depth_test=False, counting=counting, point_sprites=point_sprites
            )
            assert as_points == (len(batch) if point_sprites else 0)
            pictures.append(target.read())
    finally:
        splats.close()
        target.close()
    quads, points = pictures
    assert quads.max() > (5.0 if counting else 0.5)  # the cloud fills the texture, many splats deep
    if counting:  # edge fragments, where the kernel is 0, are discarded either way
        assert np.abs(points - quads).max() <= 1.0 and abs(points.sum() / quads.sum() - 1.0) < 1e-3
    else:
        assert np.abs(points - quads).max() < 2e-3, np.abs(points - quads).max()


def test_a_batch_is_drawn_in_its_order_as_runs_and_short_runs_of_points_stay_quads():
    mask = np.array([True] * 5 + [False] * 2 + [True] * 2 + [False] + [True] * 6)
    assert draw_runs(mask, shortest_point_run=1) == [
        (0, 5, True),
        (5, 7, False),
        (7, 9, True),
        (9, 10, False),
        (10, 16, True),
    ]
    assert draw_runs(mask, shortest_point_run=5) == [(0, 5, True), (5, 10, False), (10, 16, True)]
    assert draw_runs(mask, shortest_point_run=7) == [(0, 16, False)]
    assert draw_runs(np.zeros(0, dtype=bool)) == []


def test_splats_around_the_eye_drawn_as_points_and_quads_together_match_quads_alone(renderer):
    """A screen draw next to the eye: centres off screen and large squares keep quads, the rest are points."""
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.particles.batch import splat_batch
    from cloudcore.world.camera import frustum_planes

    rng = np.random.default_rng(8)
    around = np.column_stack([rng.uniform(-1500.0, 1500.0, (40000, 3)), rng.uniform(10.0, 60.0, 40000)])
    particles = ParticleBuffer((Cloud("around the eye", around, optical_depth=0.5),), Shading(), LIGHTS, AMBIENT)
    width, height = 160, 120
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, width / height)
    batch = splat_batch(particles, [0], CAMERA.position, frustum=frustum_planes(projection @ view))
    renderer.context.make_current()
    splats, target = SplatPass(), TextureTarget(width, height)
    try:
        pictures, as_points = [], []
        for point_sprites in (False, True):
            target.bind_cleared()
            as_points.append(splats.draw(batch, view, projection, depth_test=False, point_sprites=point_sprites))
            pictures.append(target.read())
    finally:
        splats.close()
        target.close()
    assert as_points[0] == 0 and len(batch) / 4 < as_points[1] < len(batch)  # a mixed batch
    quads, mixed = pictures
    assert quads[..., 3].mean() > 0.3
    assert np.abs(mixed - quads).max() < 2e-3, np.abs(mixed - quads).max()
