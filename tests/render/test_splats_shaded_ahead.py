"""A pass's batches shaded ahead (`SplatPass.shade_ahead`) draw as each does shaded alone, in any order, and a
batch shaded as it is drawn after them (growing the buffer they are in) leaves them as they were."""

import numpy as np

from cloudcore.model.scene import Camera, Cloud, Light, Shading
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.world.camera import projection_matrix, view_matrix

CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 60.0)
LIGHTS = (Light((0.0, 0.6, -0.8), (1.0, 0.95, 0.9), 1.0),)
AMBIENT = (0.05, 0.06, 0.09)


def _cloud(rng, name: str, count: int, x: float) -> Cloud:
    centres = rng.normal(size=(count, 3)) * [40.0, 20.0, 40.0] + [x, 0.0, -500.0]
    return Cloud(name, np.column_stack([centres, rng.uniform(5.0, 25.0, count)]), optical_depth=1.0)


def test_batches_shaded_ahead_draw_as_batches_shaded_alone(renderer):
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.particles.batch import splat_batch

    rng = np.random.default_rng(4)
    clouds = (_cloud(rng, "left", 300, -120.0), _cloud(rng, "right", 500, 120.0), _cloud(rng, "big", 5000, 0.0))
    particles = ParticleBuffer(clouds, Shading(), LIGHTS, AMBIENT)
    width, height = 96, 72
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, width / height)
    left, right, big = (splat_batch(particles, [index], CAMERA.position) for index in range(3))
    renderer.context.make_current()
    splats, target = SplatPass(), TextureTarget(width, height)

    def drawn(batch):
        target.bind_cleared()
        splats.draw(batch, view, projection, depth_test=False)
        return target.read()

    try:
        alone = [drawn(batch) for batch in (left, right)]  # each shaded as it is drawn
        splats.shade_ahead([(left, view), (right, view)])
        ahead = [drawn(right), drawn(left)]  # the other order than shaded
        after_growing = drawn(big), drawn(left)  # `big` outgrows the buffer the two are in
    finally:
        splats.close()
        target.close()
    assert alone[0][..., 3].max() > 0.2 and alone[1][..., 3].max() > 0.2
    assert np.abs(alone[0] - alone[1]).max() > 0.1  # two different pictures
    np.testing.assert_array_equal(ahead[1], alone[0])
    np.testing.assert_array_equal(ahead[0], alone[1])
    assert after_growing[0][..., 3].max() > 0.2
    np.testing.assert_array_equal(after_growing[1], alone[0])
