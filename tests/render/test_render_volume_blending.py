"""Volume-aware blending on the GL (the tiled compute pass) against its numpy reference, and a render of
two interpenetrating clouds against the ray-marched reference: nearer than plain blending."""

import dataclasses

import numpy as np
import pytest

from cloudcore.artist.particle_styles import particle_styles
from cloudcore.light.lighting import scene_lights
from cloudcore.light.volume_blending import plain_blend, ray_distances, ray_marched, volume_blend
from cloudcore.model.scene import Camera, Cloud, Light, Scene, Shading
from cloudcore.model.settings import FULL_3D
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.world.camera import pixel_rays, projection_matrix, view_matrix

WIDTH, HEIGHT = 40, 30
CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 30.0)
LIGHTS = (Light((0.3, 0.8, 0.5), (1.0, 0.9, 0.8), 1.2), Light((-0.6, -0.2, -0.7), (0.4, 0.5, 0.9), 0.6))
AMBIENT = (0.05, 0.06, 0.09)


@pytest.mark.parametrize("wall_m", [None, 101.0])
def test_the_compute_pass_composites_as_the_reference_does(renderer, wall_m):
    """Two particles half inside each other, over a coloured background; with `wall_m`, the world's
    depth is a wall that far ahead, between their centres, cutting their chords."""
    from OpenGL import GL

    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.targets import TextureTarget
    from cloudcore.gl.volume_blending import VolumeBlendingPass, batch_splats
    from cloudcore.particles.batch import splat_batch

    clouds = (
        Cloud("red", [[-1.5, 0.0, -100.0, 6.0]], optical_depth=3.0, color=(1.0, 0.3, 0.2)),
        Cloud("blue", [[1.5, 0.8, -102.0, 5.0]], optical_depth=1.5, color=(0.2, 0.4, 1.0)),
    )
    particles = ParticleBuffer(clouds, Shading(), LIGHTS, AMBIENT)
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, WIDTH / HEIGHT)
    renderer.context.make_current()
    splats, volume, target = SplatPass(), VolumeBlendingPass(), TextureTarget(WIDTH, HEIGHT)
    background = np.array([0.2, 0.3, 0.5, 1.0])
    try:
        assert volume.features.compute_shaders
        batch = splat_batch(particles, [0, 1], CAMERA.position)
        target.bind_cleared()
        GL.glClearColor(*background)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        # the target has no depth: the pass reads the frame's, cleared to the wall (or to far: no world)
        window_depth = 1.0 if wall_m is None else 0.5 * (projection[2, 2] * -wall_m + projection[2, 3]) / wall_m + 0.5
        renderer.context.bind_target()
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearDepth(window_depth)
        GL.glClear(GL.GL_DEPTH_BUFFER_BIT)
        GL.glClearDepth(1.0)
        assert volume.draw(
            (*splats.shade(batch, view), len(batch)),
            view,
            projection,
            target.texture,
            renderer.context.framebuffer,
            (WIDTH, HEIGHT),
        )
        pixels = target.read()
    finally:
        splats.close(), volume.close(), target.close()
    rays = pixel_rays(CAMERA, WIDTH, HEIGHT).reshape(-1, 3)
    drawn, behind = batch_splats(batch, view), np.tile(background, (len(rays), 1))
    opaque = ray_distances(np.full(len(rays), window_depth), rays, view, projection)
    expected = volume_blend(drawn, rays, behind, opaque).reshape(pixels.shape)
    plain = plain_blend(drawn, rays, behind, opaque).reshape(pixels.shape)
    assert np.abs(expected - plain).max() > 0.02  # the particles do interpenetrate
    np.testing.assert_allclose(pixels, expected, atol=4e-3)


def interpenetrating_clouds() -> Scene:
    """Two balls of 50 particles each, of different colours and densities, half inside each other."""
    generator = np.random.default_rng(5)
    balls = generator.normal(0.0, 12.0, (2, 50, 3)) + [[[-10.0, 700.0, -300.0]], [[10.0, 703.0, -305.0]]]
    radii = generator.uniform(8.0, 14.0, (2, 50, 1))
    warm = Cloud("warm", np.concatenate([balls[0], radii[0]], axis=1), optical_depth=6.0, color=(1.0, 0.55, 0.35))
    cool = Cloud("cool", np.concatenate([balls[1], radii[1]], axis=1), optical_depth=3.0, color=(0.35, 0.55, 1.0))
    return Scene(clouds=(warm, cool), camera=Camera((0.0, 700.0, -160.0), (0.0, 700.0, -300.0), 40.0), terrain=None)


def fog_on_the_ground() -> Scene:
    """A flat layer of particles half sunk into the default terrain, seen from just above."""
    from cloudcore.model.scene import Terrain
    from cloudcore.world.terrain import height_at

    terrain = Terrain()
    ground = float(height_at(terrain, np.array([0.0]), np.array([-300.0]))[0])
    generator = np.random.default_rng(9)
    layer = generator.uniform([-40.0, ground - 4.0, -330.0, 10.0], [40.0, ground + 6.0, -270.0, 16.0], (60, 4))
    eye = (0.0, ground + 25.0, -180.0)
    return Scene(clouds=(Cloud("fog", layer),), camera=Camera(eye, (0.0, ground, -300.0), 40.0), terrain=terrain)


@pytest.mark.parametrize("make_scene, ratio", [(interpenetrating_clouds, 0.75), (fog_on_the_ground, 0.25)])
def test_volumes_are_nearer_the_ray_march_than_billboards(renderer, make_scene, ratio):
    """Two clouds sharing space (colours mixed where they meet), and a layer cut by the terrain (a
    billboard's hard line where its plane meets the ground, a volume's chord cut softly)."""
    from cloudcore.gl.volume_blending import batch_splats
    from cloudcore.particles.batch import splat_batch
    from cloudcore.world.camera import frustum_planes

    scene = make_scene()
    width, height = renderer.size
    images = {}
    # the ray march composites the clouds over the ground as drawn without them: no cloud shadows on either side
    unshadowed = dataclasses.replace(FULL_3D, cloud_shadows=False)
    for blending in ("plain", "volume"):
        _, stats = renderer.render(scene, settings=dataclasses.replace(unshadowed, blending=blending))
        images[blending] = renderer.context.read_linear_rgb().reshape(-1, 3)
        assert stats.particles_as_volumes == (stats.particles_drawn if blending == "volume" else 0)
    renderer.render(dataclasses.replace(scene, clouds=()), settings=unshadowed)
    background = np.column_stack([renderer.context.read_linear_rgb().reshape(-1, 3), np.zeros(width * height)])
    window_depth = renderer.context.read_depth()
    lights, ambient = scene_lights(scene.lighting)
    particles = ParticleBuffer(
        scene.clouds, scene.shading, lights, ambient, styles=particle_styles(scene.clouds, scene.lighting)
    )
    view = view_matrix(scene.camera)
    frustum = frustum_planes(projection_matrix(scene.camera.fov_y_deg, width / height) @ view)
    batch = splat_batch(particles, range(len(scene.clouds)), scene.camera.position, time_s=0.0, frustum=frustum)
    drawn, rays = batch_splats(batch, view), pixel_rays(scene.camera, width, height).reshape(-1, 3)
    opaque = ray_distances(window_depth, rays, view, projection_matrix(scene.camera.fov_y_deg, width / height))
    reference = ray_marched(drawn, rays, background, opaque, steps=512)[:, :3]
    errors = {name: float(np.sqrt(np.mean((image - reference) ** 2))) for name, image in images.items()}
    assert errors["volume"] < ratio * errors["plain"], errors
    # each path draws its numpy reference's picture
    for name, blend in (("plain", plain_blend), ("volume", volume_blend)):
        difference = np.abs(images[name] - blend(drawn, rays, background, opaque)[:, :3]).max()
        assert difference < 0.02, (name, difference)


def test_sprites_fall_back_to_billboards(renderer):
    """The volume pass draws Gaussian splats of one colour: a batch with atlas sprites is drawn plain."""
    from cloudcore.artist.sprites import SpriteStyle

    scene = interpenetrating_clouds()
    sprites = dataclasses.replace(scene.clouds[0], sprite=SpriteStyle())
    scene = dataclasses.replace(scene, clouds=(sprites, scene.clouds[1]))
    pictures = {}
    for blending in ("plain", "volume"):
        # one order for both ("auto" takes the way it measured faster, and the GPU's sort rounds apart by a level)
        settings = dataclasses.replace(FULL_3D, blending=blending, splat_order="cpu")
        pictures[blending], stats = renderer.render(scene, settings=settings)
        assert stats.particles_drawn > 0 and stats.particles_as_volumes == 0
    np.testing.assert_array_equal(pictures["plain"], pictures["volume"])


def test_a_crossfading_unit_composites_its_full_3d_layer_as_volumes(renderer):
    """The full-3D image a unit fades in from its impostor goes through the volume pass too (into the
    screen layer): mid-fade the frame is the plan's weighted mean of the volume picture and the impostor."""
    from cloudcore.model.settings import RenderSettings
    from cloudcore.scenes.files import load_scene
    from cloudcore.world.navigation import orbited
    from tests.conftest import VALLEY
    from tests.render.test_render_lod import FULL_CHEAP
    from tests.unit.lod.test_frameplan import FILL_BOUND

    valley = load_scene(VALLEY)
    cloud = valley.clouds[5]
    centre, radius = cloud.bounding_sphere()
    scene = dataclasses.replace(valley, clouds=(cloud,), terrain=None)
    auto = RenderSettings(
        ring_radius=np.inf, transition_frames=5, translation_metric="centre", tolerance_deg=1.0, blending="volume"
    )
    made_from = Camera(tuple(centre + [0.0, 0.0, 3.0 * radius]), tuple(centre), 60.0)
    camera = orbited(made_from, 0.75)
    renderer.render(scene, camera=made_from, settings=dataclasses.replace(auto, mode="impostor"))
    full, impostor = (
        renderer.render(scene, camera=camera, settings=dataclasses.replace(auto, mode=mode))[0].astype(float).mean()
        for mode in ("full", "impostor")
    )
    for costs in (FILL_BOUND, FULL_CHEAP, FULL_CHEAP):
        image, stats = renderer.render(scene, camera=camera, settings=auto, costs=costs)
    weight = renderer.last_plan.clouds[0].full_weight
    assert 0.0 < weight < 1.0 and renderer.last_plan.clouds[0].kind == "crossfade"
    assert stats.particles_as_volumes == stats.particles_drawn > 0
    assert image.astype(float).mean() == pytest.approx(weight * full + (1 - weight) * impostor, abs=0.01)
