"""The clouds' shadow baked on the ground (`cloudcore.gl.ground_shadows`): the texture at its texels' centres is the
clouds' map read there, the terrain drawn from it is the terrain drawn from the map, and a held map is baked once."""

import dataclasses

import numpy as np
import pytest

from cloudcore.gl import FrameRenderer, frame
from cloudcore.light.cloud_shadows import sample_map
from cloudcore.measure.imagecompare import compare
from cloudcore.model.cloud_records import Formation
from cloudcore.model.settings import FULL_3D
from cloudcore.scenes.files import load_scene
from cloudcore.world.terrain import height_at
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH, VALLEY
from tests.render.test_cloud_shadows import shadow_scene

pytestmark = pytest.mark.gl


def map_read_at_the_texels_centres(renderer, terrain) -> np.ndarray:
    """(across, along): the share of the sun the renderer's clouds' map lets reach the ground of `terrain` at the
    centre of each texel of its baked texture, read from the map as the terrain's pixels read it unbaked."""
    frame = renderer.ground_shadows.frame
    xz = frame.texel_centres().reshape(-1, 2)
    points = np.column_stack([xz[:, 0], height_at(terrain, xz[:, 0], xz[:, 1]), xz[:, 1]])
    shadow_map = renderer.shadow_map
    return np.exp(-sample_map(shadow_map.space, shadow_map.read(), points)).reshape(frame.size[1], frame.size[0])


def test_the_baked_shadow_is_the_map_read_at_its_texels_centres(renderer):
    scene, _, _ = shadow_scene()
    renderer.render(scene, settings=FULL_3D, read_back=False)
    renderer.context.make_current()
    baked, frame = renderer.ground_shadows.read(), renderer.ground_shadows.frame
    assert baked.shape == (frame.size[1], frame.size[0])
    expected = map_read_at_the_texels_centres(renderer, scene.terrain)
    assert expected.min() < 0.2 and expected.max() == 1.0  # a shadow, and the ground around it
    error = np.abs(baked - expected)
    # 8 bits, and the terrain's triangles a metre off the ground's height where the shadow's edge is steep
    assert np.quantile(error, 0.99) < 2.0 / 255.0
    assert error.max() < 0.05


def test_the_terrain_drawn_from_the_bake_is_the_terrain_drawn_from_the_map(renderer, monkeypatch):
    """The same frame with the map read per pixel (as a map remade every frame is) and from the bake: within 45 dB,
    and not the same bytes (the bake holds 8 bits); a steady map held is not baked again."""
    scene, _, _ = shadow_scene()
    without, _ = renderer.render(scene, settings=dataclasses.replace(FULL_3D, cloud_shadows=False))
    baked_pictures = [renderer.render(scene, settings=FULL_3D)[0] for _ in range(2)]
    baked = renderer.ground_shadows.baked
    monkeypatch.setattr(frame, "steady_map", lambda *args, **kwargs: False)
    read, _ = renderer.render(scene, settings=FULL_3D)
    assert compare(read, without).psnr_db < 30.0  # the shadow is there
    assert not np.array_equal(baked_pictures[0], read)
    assert compare(baked_pictures[0], read).psnr_db > 45.0
    assert np.array_equal(baked_pictures[1], baked_pictures[0])
    assert renderer.ground_shadows.baked == baked


def test_a_forming_cloud_s_map_is_read_per_pixel(renderer):
    scene, _, _ = shadow_scene()
    cloud = dataclasses.replace(scene.clouds[0], formation=Formation("form", start_s=0.0, duration_s=60.0))
    scene = dataclasses.replace(scene, clouds=(cloud,))
    baked = renderer.ground_shadows.baked if renderer.ground_shadows is not None else 0
    for time_s in (10.0, 20.0):
        renderer.render(scene, settings=FULL_3D, time_s=time_s, read_back=False)
    assert renderer.ground_shadows.baked == baked


def test_a_moved_eye_bakes_only_the_tiles_it_did_not_hold_and_gets_a_fresh_bake_s_texture(renderer):
    """Over hills of 300 m the eye's descent splits the tiles: the new ones alone are baked over the old ones'
    ground, and the texture is the one a renderer that baked these tiles afresh holds."""
    scene, _, _ = shadow_scene()
    scene = dataclasses.replace(scene, terrain=dataclasses.replace(scene.terrain, height=300.0))
    renderer.render(scene, settings=FULL_3D, read_back=False)
    eye = np.asarray(scene.camera.position) + [3000.0, -2500.0, 0.0]
    moved = dataclasses.replace(scene.camera, position=tuple(eye))
    baked = renderer.ground_shadows.baked
    renderer.render(scene, settings=FULL_3D, camera=moved, read_back=False)
    assert renderer.ground_shadows.baked == baked + 1
    renderer.context.make_current()
    after = renderer.ground_shadows.read()
    with FrameRenderer(RENDER_WIDTH, RENDER_HEIGHT) as fresh:
        fresh.render(scene, settings=FULL_3D, camera=moved, read_back=False)
        assert fresh.ground_shadows.baked == 1
        fresh.context.make_current()
        afresh = fresh.ground_shadows.read()
    renderer.context.make_current()
    assert after.shape == afresh.shape and after.min() < 0.2
    # the same values but at a few texels on the tiles' edges, which either tile may draw
    assert np.mean(after != afresh) < 0.01
    assert np.abs(after - afresh).max() < 0.05
    # no texel left out between tiles of two levels (a lit speck in a shadow): the map's read there
    expected = map_read_at_the_texels_centres(renderer, scene.terrain)
    assert expected.shape == after.shape
    assert np.abs(afresh - expected).max() < 0.5


def test_no_texel_between_the_default_view_s_tiles_is_left_out_of_the_bake(renderer):
    """The default view's tiles of several levels meet along edges the coarser samples half as often: a texel
    there that no triangle covered stayed clear, a lit speck inside a shadow (one at 640x480 before the tiles'
    edges were drawn as lines first)."""
    renderer.render(load_scene(VALLEY), settings=FULL_3D, read_back=False)
    renderer.context.make_current()
    baked = renderer.ground_shadows.read()
    neighbours = np.stack([baked[:-2, 1:-1], baked[2:, 1:-1], baked[1:-1, :-2], baked[1:-1, 2:]])
    assert baked.min() < 0.2
    assert not np.any(baked[1:-1, 1:-1] - neighbours.max(axis=0) > 0.3)
