"""The impostor atlas on the GPU: cells keep their texels when the texture grows and shrinks, quads sample only
their own cell, and a frame's impostors share it."""

import types

import numpy as np
from OpenGL import GL

from cloudcore.gl.impostor_atlas import INSTANCE_FLOATS, AtlasImage, ImpostorAtlas, atlas_instances
from cloudcore.gl.quads import QuadPass
from cloudcore.gl.targets import TextureTarget
from cloudcore.lod.atlas import Cell
from cloudcore.lod.impostors import cropped_corners
from cloudcore.model.settings import RenderSettings
from cloudcore.scenes.files import load_scene
from tests.conftest import VALLEY
from tests.unit.lod.test_atlas import overlaps


def fill(image: AtlasImage, colour) -> None:
    image.bind_cleared()
    GL.glClearColor(*colour)
    GL.glClear(GL.GL_COLOR_BUFFER_BIT)
    GL.glDisable(GL.GL_SCISSOR_TEST)


def test_cells_keep_their_texels_while_the_atlas_grows_and_shrinks(renderer):
    renderer.context.make_current()
    atlas = ImpostorAtlas(64)
    try:
        colours = [(0.1 * i, 0.2, 1.0 - 0.1 * i, 0.5) for i in range(5)]
        images = []
        for colour, side in zip(colours, (64, 20, 40, 64, 20)):
            images.append(atlas.allocate(side))  # layers 1, 2, 4, 4, 4: two copies on the way
            fill(images[-1], colour)
        assert [image.cell.layer for image in images] == [0, 1, 2, 3, 1]
        assert atlas.layout.layers == 4 and atlas.nbytes == 4 * 64 * 64 * 8
        for image, colour in zip(images, colours):
            np.testing.assert_allclose(image.read(), np.broadcast_to(colour, (image.side, image.side, 4)), atol=1e-3)
        for image in (images[0], images[2], images[3]):
            atlas.release(image)
        assert atlas.layout.layers == 2  # the top half free, a quarter in use at most: halved, copied
        for image, colour in zip((images[1], images[4]), (colours[1], colours[4])):
            np.testing.assert_allclose(image.read(), np.broadcast_to(colour, (image.side, image.side, 4)), atol=1e-3)
    finally:
        atlas.close()


def test_an_instance_samples_its_own_texels_clamped_half_a_texel_inside_them():
    atlas = types.SimpleNamespace(layer_side=512)
    image = AtlasImage(atlas, Cell(layer=3, y=256, x=128, side=128), side=100)
    corners = np.arange(12.0).reshape(4, 3)
    (instance,) = atlas_instances([image], corners[None], [0.75], np.array([(0.0, 0.5, 1.0, 1.0)]))
    assert instance.shape == (INSTANCE_FLOATS,) and instance.dtype == np.float32
    np.testing.assert_array_equal(instance[:12], corners.ravel())
    np.testing.assert_allclose(instance[12:16], np.array([128, 306, 228, 356]) / 512, rtol=1e-6)
    np.testing.assert_allclose(instance[16:20], np.array([128.5, 256.5, 227.5, 355.5]) / 512, rtol=1e-6)
    assert tuple(instance[20:]) == (0.75, 3.0)


def test_a_frames_impostors_lie_in_separate_cells_of_one_atlas(renderer):
    renderer.lod_state = type(renderer.lod_state)()
    renderer.render(load_scene(VALLEY), settings=RenderSettings(mode="impostor"), read_back=False)
    plan, store = renderer.last_plan, renderer._impostors  # the store's lookups are public, not its handle
    images = [store.cloud_impostor(cloud.members)[0] for cloud in plan.of_kind("impostor")]
    assert len(images) > 10 and len({id(image.atlas) for image in images}) == 1
    cells = [image.cell for image in images]
    assert len(set(cells)) == len(cells)
    assert not any(overlaps(a, b) for i, a in enumerate(cells) for b in cells[i + 1 :])
    assert all(image.side <= image.cell.side for image in images)
    assert renderer.texture_bytes >= images[0].atlas.nbytes > 0


def test_a_target_drawn_after_an_atlas_cell_is_not_clipped_to_the_cell(renderer):
    """A cell's scissor stays on for its splats; the ring's segment targets rendered after it in the same
    update must still be cleared and drawn whole (they were clipped to the last cell once)."""
    renderer.context.make_current()
    atlas, target = ImpostorAtlas(64), TextureTarget(48, 32)
    try:
        atlas.allocate(16).bind_cleared()
        target.bind_cleared()
        GL.glClearColor(0.25, 0.5, 0.75, 1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        np.testing.assert_allclose(target.read(), np.broadcast_to((0.25, 0.5, 0.75, 1.0), (32, 48, 4)), atol=1e-3)
    finally:
        atlas.close()
        target.close()


def _twenty_clouds(rng):
    """Twenty small clouds ahead of the eye at the origin, the eighth of sprites, as a `ParticleBuffer`."""
    from cloudcore.model.cloud_records import SpriteStyle
    from cloudcore.model.scene import Cloud, Light, Shading
    from cloudcore.particles.buffer import ParticleBuffer

    clouds = []
    for index in range(20):
        centre = [(index % 5 - 2) * 150.0, (index // 5) * 80.0, -700.0 - 40.0 * index]
        centres = rng.normal(size=(60, 3)) * [30.0, 12.0, 30.0] + centre
        style = {"sprite": SpriteStyle(rows=(0,))} if index == 7 else {}
        clouds.append(Cloud(f"c{index}", np.column_stack([centres, rng.uniform(6.0, 14.0, 60)]), **style))
    light = Light((0.0, 0.6, -0.8), (1.0, 0.95, 0.9), 1.0)
    return ParticleBuffer(clouds, Shading(), (light,), (0.05, 0.06, 0.09))


def _impostor_view_of(particles, cloud: int, eye):
    from cloudcore.lod.impostors import impostor_view

    start, stop = particles.cloud_starts[cloud : cloud + 2]
    centre = particles.centres[start:stop].mean(axis=0)
    reach = np.linalg.norm(particles.centres[start:stop] - centre, axis=1) + particles.radii[start:stop]
    return impostor_view(centre, reach.max(), eye)


def test_cells_drawn_in_one_multi_draw_hold_what_each_drawn_alone_holds(renderer):
    """A frame's regenerations all of point sprites go into the atlas in one multi-draw a 16 cells, each through
    its own viewport, scissor and layer (`SplatPass.draw_point_cells`): the texels must be those of drawing each
    cell by itself, none spilling into a neighbour; a cloud of sprites still needs quads, so a draw of its own."""
    from cloudcore.gl.splats import SplatPass
    from cloudcore.particles.batch import splat_batch

    rng = np.random.default_rng(11)
    particles = _twenty_clouds(rng)
    clouds = range(20)
    eye = np.zeros(3)
    renderer.context.make_current()
    atlas, splats = ImpostorAtlas(128), SplatPass()
    try:
        images = [atlas.allocate(int(side)) for side in rng.choice([16, 24, 40, 64], len(clouds))]
        renders = []
        for index, image in enumerate(images):
            view = _impostor_view_of(particles, index, eye)
            renders.append((image, splat_batch(particles, [index], eye), view.view, view.projection))
        splats.shade_ahead([(batch, view) for _, batch, view, _ in renders])
        alone = []
        for image, batch, view, projection in renders:
            image.bind_cleared()
            splats.draw(batch, view, projection, depth_test=False)
            alone.append(image.read())
        as_points, drawn = [], []
        for index, (image, batch, view, projection) in enumerate(renders):
            image.bind_cleared()
            points = splats.as_points_in(batch, view, projection, image.viewport)
            if points is not None:
                as_points.append((batch, view, *points, image.viewport, image.cell.layer))
                drawn.append(index)
        # the sprites need quads, as do clouds with splats under a pixel in the smallest cells: two multi-draws
        assert 7 not in drawn and len(drawn) > 16
        atlas.bind_layers()
        splats.draw_point_cells(as_points)
        GL.glDisable(GL.GL_SCISSOR_TEST)
        for index, (image, expected) in enumerate(zip(images, alone)):
            held = image.read()
            if index not in drawn:
                assert not held.any()  # cleared, not drawn: nothing spilled in from a neighbour
                continue
            assert expected[..., 3].max() > 0.1, index
            np.testing.assert_allclose(held, expected, atol=2e-3, err_msg=f"cell {index}")
    finally:
        splats.close()
        atlas.close()


def test_cells_chosen_and_sorted_on_the_gpu_hold_what_each_drawn_alone_holds(renderer):
    """The GPU's way for a frame's regenerations (`splat_order = "gpu"`): one selection of every cell, one
    sort, one multi-draw of quads a 16 cells (`SplatPass.draw_cells`).  Each cell must hold the particles
    `splat_batch` chooses for it, far to near, and the texels of drawing it alone as quads; a cloud split in two
    layers is in two cells, and the sprites' cell shares the draw."""
    from cloudcore.gl.splats import SplatPass
    from cloudcore.particles.batch import SplatSelection, splat_batch

    rng = np.random.default_rng(12)
    particles = _twenty_clouds(rng)
    eye = np.zeros(3)
    middle = float(
        np.median(np.linalg.norm(particles.centres[particles.cloud_starts[3] : particles.cloud_starts[4]], axis=1))
    )
    # (cloud, depth range): the fourth in two layers, 21 cells in all
    cells = [(3, (-1.0, middle)), (3, (middle, np.inf))] + [
        (cloud, (-1.0, np.inf)) for cloud in range(20) if cloud != 3
    ]
    renderer.context.make_current()
    atlas, splats = ImpostorAtlas(128), SplatPass()
    try:
        images = [atlas.allocate(int(side)) for side in rng.choice([24, 40, 64], len(cells))]
        views = [_impostor_view_of(particles, cloud, eye) for cloud, _ in cells]
        batches = [splat_batch(particles, [cloud], eye, [depth]) for cloud, depth in cells]
        selection = SplatSelection(
            particles, tuple(c for c, _ in cells), eye, tuple(d for _, d in cells), None, None, tuple(range(len(cells)))
        )
        stacked = np.array([view.view for view in views])
        for index, (chosen, batch) in enumerate(zip(splats.read_orders(selection, stacked), batches)):
            assert len(batch) > 20 and set(chosen.tolist()) == set(batch.order.tolist()), index
            distances = np.linalg.norm(particles.centres[chosen] - eye, axis=1)
            assert np.all(distances[1:] <= distances[:-1] * (1.0 + 4e-7) + 1e-4), index
        alone = []
        for image, batch, view in zip(images, batches, views):
            image.bind_cleared()
            splats.draw(batch, view.view, view.projection, depth_test=False, point_sprites=False)
            alone.append(image.read())
        for image in images:
            image.bind_cleared()
        atlas.bind_layers()
        splats.draw_cells(
            selection,
            stacked,
            [(view.projection, image.viewport, image.cell.layer) for view, image in zip(views, images)],
        )
        GL.glDisable(GL.GL_SCISSOR_TEST)
        for index, (image, expected) in enumerate(zip(images, alone)):
            assert expected[..., 3].max() > 0.1, index
            np.testing.assert_allclose(image.read(), expected, atol=2e-3, err_msg=f"cell {index}")
        assert splats.take_selected() == (0, sum(len(batch) for batch in batches))
    finally:
        splats.close()
        atlas.close()


def test_a_frames_instances_made_at_once_are_each_made_alone():
    """`atlas_instances` and `cropped_corners` over many quads give, row by row, what each gives alone."""
    atlas = types.SimpleNamespace(layer_side=256)
    rng = np.random.default_rng(3)
    images = [AtlasImage(atlas, Cell(layer=i, y=32 * i, x=64, side=64), side=40 + i) for i in range(5)]
    corners = rng.normal(size=(5, 4, 3))
    u, v = np.sort(rng.uniform(size=(5, 2)), axis=1), np.sort(rng.uniform(size=(5, 2)), axis=1)
    extents = np.column_stack([u[:, 0], v[:, 0], u[:, 1], v[:, 1]])  # u0, v0, u1, v1
    weights = rng.uniform(size=5)
    cropped = cropped_corners(corners, extents)
    together = atlas_instances(images, cropped, weights, extents)
    for i in range(5):
        alone = cropped_corners(corners[i], tuple(extents[i]))
        np.testing.assert_allclose(cropped[i], alone, rtol=1e-12, atol=1e-12)
        u0, v0, u1, v1 = extents[i]  # the quad's corners at the extent's, on its plane
        origin, right, up = corners[i, 0], corners[i, 1] - corners[i, 0], corners[i, 2] - corners[i, 0]
        np.testing.assert_allclose(alone[3], origin + u1 * right + v1 * up, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(
            together[i], atlas_instances([images[i]], alone[None], [weights[i]], extents[i : i + 1])[0]
        )


def test_an_impostor_weighed_over_one_never_darkens_what_lies_behind_it(renderer):
    """A field's cloud faded in since its impostor was made draws it weighed over 1 (`FrameRenderer._faded`): its
    opacity stops at 1, its colour scaled as far, so a grey half-transparent impostor weighed 3 over white shows
    its colour doubled and opaque, never the white behind it taken away (0.25 where the opacity reached 1.5)."""
    renderer.context.make_current()
    quads = QuadPass()
    impostor, target = TextureTarget(4, 4), TextureTarget(4, 4)
    try:
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, impostor.framebuffer)
        GL.glViewport(0, 0, 4, 4)
        GL.glClearColor(0.25, 0.25, 0.25, 0.5)  # premultiplied: a grey of 0.5 at half opacity
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, target.framebuffer)
        GL.glClearColor(1.0, 1.0, 1.0, 1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        screen = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
        quads.draw(screen, np.eye(4), impostor.texture, 3.0, depth_test=False)
        np.testing.assert_allclose(target.read()[..., :3], 0.5, atol=1e-3)
    finally:
        for held in (impostor, target):
            held.close()
        quads.close()
