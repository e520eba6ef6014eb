"""The clouds' shadow baked on the ground (`cloudcore.light.ground_shadows`): the texture's frame covers every
ground point the clouds' map may shadow, finer than the map, and the bake plan bakes a steady map once, then only
the tiles it lacks, and no other map."""

import numpy as np
import pytest

from cloudcore.light.cloud_shadows import MAP_RESOLUTION, light_space
from cloudcore.light.ground_shadows import (
    MOST_TEXELS,
    TEXELS_PER_MAP_TEXEL,
    BakePlan,
    ground_shadow_frame,
    steady_map,
    tile_keys,
)
from cloudcore.world.sun import sun_direction

LOWEST, HIGHEST, HALF_SIDE = 0.0, 1500.0, 40_000.0


def cloud_space(hours: float):
    rng = np.random.default_rng(3)
    centres = rng.uniform([-2500.0, 900.0, -2000.0], [2500.0, 1800.0, 2000.0], (200, 3))
    return light_space(centres, rng.uniform(50.0, 200.0, 200), sun_direction(hours), MAP_RESOLUTION)


@pytest.mark.parametrize("hours", [8.0, 12.0, 15.5, 18.25])
def test_every_ground_point_on_the_map_lies_in_the_texture(hours):
    """Points between the lowest and highest ground whose place on the map is within it, or within a texel of its
    border, are inside the texture's frame; its level axes ignore the height."""
    space = cloud_space(hours)
    frame = ground_shadow_frame(space, LOWEST, HIGHEST, HALF_SIDE)
    rng = np.random.default_rng(1)
    points = np.column_stack(
        [
            rng.uniform(-20_000, 20_000, 200_000),
            rng.uniform(LOWEST, HIGHEST, 200_000),
            rng.uniform(-20_000, 20_000, 200_000),
        ]
    )
    x, y, _ = space.texel_coordinates(points)
    width, height = space.size
    on_map = (x > -1.0) & (x < width + 1.0) & (y > -1.0) & (y < height + 1.0)
    assert on_map.sum() > 1000
    i, j = frame.texel_coordinates(points[on_map])
    assert np.all((i >= 0) & (i <= frame.size[0]) & (j >= 0) & (j <= frame.size[1]))
    raised = points + [0.0, 500.0, 0.0]
    assert np.allclose(frame.texel_coordinates(raised), frame.texel_coordinates(points))
    u, v, zero, one = frame.world_to_texture() @ np.column_stack([points[:5], np.ones(5)]).T
    i, j = frame.texel_coordinates(points[:5])
    assert np.allclose(u * frame.size[0], i) and np.allclose(v * frame.size[1], j)
    assert np.all(zero == 0.0) and np.all(one == 1.0)


@pytest.mark.parametrize("hours", [8.0, 15.5])
def test_the_texture_is_finer_than_the_map_on_the_ground(hours):
    """A step of one texel along either level axis moves a ground point by at most 1 / TEXELS_PER_MAP_TEXEL of the
    map's texels, and by that much along one of them: no finer than it needs."""
    space = cloud_space(hours)
    frame = ground_shadow_frame(space, LOWEST, HIGHEST, HALF_SIDE)
    for axis, texel_m in zip((frame.along, frame.across), frame.texel_m, strict=True):
        start = np.array([[100.0, 300.0, -200.0]])
        x0, y0, _ = space.texel_coordinates(start)
        x1, y1, _ = space.texel_coordinates(start + texel_m * np.asarray(axis))
        moved = max(abs(float(x1[0] - x0[0])), abs(float(y1[0] - y0[0])))
        assert moved == pytest.approx(1.0 / TEXELS_PER_MAP_TEXEL)


def test_a_sun_at_the_horizon_bakes_the_whole_square_at_most_texels():
    space = cloud_space(12.0)
    level = space.__class__(**{**space.__dict__, "forward": (1.0, 0.0, 0.0)})
    frame = ground_shadow_frame(level, LOWEST, HIGHEST, 1000.0)
    corners = np.array([[x, 0.0, z] for x in (-1000.0, 1000.0) for z in (-1000.0, 1000.0)])
    i, j = frame.texel_coordinates(corners)
    assert np.all((i > -1e-6) & (i < frame.size[0] + 1e-6) & (j > -1e-6) & (j < frame.size[1] + 1e-6))
    wide = ground_shadow_frame(level, LOWEST, HIGHEST, 1e6)
    assert max(wide.size) <= MOST_TEXELS


def test_tile_keys_tell_tiles_apart():
    tiles = np.array([[0, 5, 7], [1, 5, 7], [0, 7, 5], [6, 0, 0], [0, 0, 1]])
    assert len(np.unique(tile_keys(tiles))) == len(tiles)


def test_a_steady_map_is_baked_at_once_then_only_the_tiles_it_lacks():
    plan = BakePlan()
    keys = tile_keys(np.array([[0, 0, 0], [0, 1, 0], [1, 1, 1]]))
    first = plan.step("map 1", keys, steady=True)
    assert first.read_baked and first.afresh and first.tiles.tolist() == [0, 1, 2]
    held = plan.step("map 1", keys, steady=True)
    assert held.read_baked and not held.afresh and not len(held.tiles)
    # the eye moves: a tile splits into four, one tile stays
    moved = tile_keys(np.array([[0, 0, 0], [0, 2, 2], [0, 2, 3], [0, 3, 2], [0, 3, 3]]))
    step = plan.step("map 1", moved, steady=True)
    assert step.read_baked and not step.afresh and step.tiles.tolist() == [1, 2, 3, 4]
    # a dropped tile that comes back is baked again (its ground was baked over by the tiles that replaced it)
    assert plan.step("map 1", keys, steady=True).tiles.tolist() == [1, 2]
    # a new map: all of it
    assert plan.step("map 2", keys, steady=True).afresh


def test_a_map_that_is_not_steady_is_read_per_pixel_and_never_baked():
    plan = BakePlan()
    keys = tile_keys(np.array([[0, 0, 0]]))
    assert not any(plan.step(("map", frame), keys, steady=False).read_baked for frame in range(3))
    assert not len(plan.step(("map", 2), keys, steady=False).tiles)
    assert plan.step(("map", 2), keys, steady=True).afresh


@pytest.mark.parametrize(
    "kind", [dict(preview=True), dict(field=True), dict(moving=True), dict(forming=True)], ids=lambda k: next(iter(k))
)
def test_a_map_remade_or_moved_every_frame_is_not_steady(kind):
    still = dict(preview=False, field=False, moving=False, forming=False)
    assert steady_map(**still)
    assert not steady_map(**(still | kind))
