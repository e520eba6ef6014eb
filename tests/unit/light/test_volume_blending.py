"""Yusov's volume-aware blending (numpy): plain blending where particles are apart, the ray-marched
reference where they interpenetrate, finite at the extremes."""

import numpy as np
import pytest

from cloudcore.light.volume_blending import (
    MAX_OPTICAL_DEPTH,
    TILE_PIXELS,
    Splats,
    blending_path,
    particle_segments,
    plain_blend,
    ray_distances,
    ray_marched,
    ray_marched_in_tiles,
    screen_tiles,
    volume_blend,
)
from cloudcore.model.scene import Camera
from cloudcore.world.camera import NEAR_PLANE_M, pixel_rays, projection_matrix, view_matrix

WIDTH, HEIGHT = 40, 30
CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 30.0)
RAYS = pixel_rays(CAMERA, WIDTH, HEIGHT).reshape(-1, 3)
RIGHT, UP = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
BACKGROUND = np.tile([0.2, 0.3, 0.5, 1.0], (WIDTH * HEIGHT, 1))


def splats(centres, radii, colours, opacities) -> Splats:
    """Particles relative to the eye at the origin, sorted far to near as a batch is."""
    centres = np.asarray(centres, dtype=np.float64)
    order = np.argsort(-np.linalg.norm(centres, axis=1), kind="stable")
    opacities = np.asarray(opacities, dtype=np.float64)
    colours = np.asarray(colours, dtype=np.float64) * opacities[:, None]
    radii = np.asarray(radii, dtype=np.float64)
    return Splats(centres[order], radii[order], colours[order], opacities[order], RIGHT, UP)


RED_BLUE = ([[1.0, 0.1, 0.1], [0.1, 0.2, 1.0]], [0.9, 0.7])


def test_particles_apart_blend_as_billboards():
    pair = splats([[-8.0, 0.0, -100.0], [8.0, 1.0, -112.0]], [6.0, 7.0], *RED_BLUE)
    np.testing.assert_allclose(volume_blend(pair, RAYS, BACKGROUND), plain_blend(pair, RAYS, BACKGROUND), atol=1e-12)
    np.testing.assert_allclose(ray_marched(pair, RAYS, BACKGROUND), plain_blend(pair, RAYS, BACKGROUND), atol=1e-9)


def test_one_behind_the_other_without_touching_blends_as_billboards():
    pair = splats([[0.0, 0.0, -100.0], [1.0, 0.0, -120.0]], [6.0, 6.0], *RED_BLUE)
    np.testing.assert_allclose(volume_blend(pair, RAYS, BACKGROUND), plain_blend(pair, RAYS, BACKGROUND), atol=1e-12)


@pytest.mark.parametrize("offset", [0.0, 2.0, 5.0])
def test_interpenetrating_particles_match_the_ray_march_and_billboards_do_not(offset):
    pair = splats([[-1.0, 0.0, -100.0], [1.0, 0.5, -100.0 - offset]], [6.0, 5.0], *RED_BLUE)
    reference = ray_marched(pair, RAYS, BACKGROUND, steps=2048)
    volume_error = np.abs(volume_blend(pair, RAYS, BACKGROUND) - reference).max()
    plain_error = np.abs(plain_blend(pair, RAYS, BACKGROUND) - reference).max()
    assert volume_error < 1e-3, (volume_error, plain_error)
    assert plain_error > 0.03, (volume_error, plain_error)


def test_holding_the_front_or_yusovs_merged_volume_is_the_same_for_two_particles():
    pair = splats([[-1.0, 0.0, -100.0], [1.0, 0.5, -102.0]], [6.0, 5.0], *RED_BLUE)
    front = volume_blend(pair, RAYS, BACKGROUND, hold="front")
    np.testing.assert_allclose(volume_blend(pair, RAYS, BACKGROUND, hold="merged"), front, atol=1e-12)
    with pytest.raises(ValueError, match="hold must be one of"):
        volume_blend(pair, RAYS, BACKGROUND, hold="both")


def test_the_ray_march_converges_to_the_volume_compositing():
    pair = splats([[-1.0, 0.0, -100.0], [1.0, 0.5, -102.0]], [6.0, 5.0], *RED_BLUE)
    volume = volume_blend(pair, RAYS, BACKGROUND)
    errors = [np.abs(ray_marched(pair, RAYS, BACKGROUND, steps=steps) - volume).max() for steps in (16, 64, 256)]
    assert errors[0] > errors[1] > errors[2], errors


@pytest.mark.parametrize("spread, ratio", [(8.0, 0.5), (2.0, 0.97)])
def test_a_cloud_of_interpenetrating_particles_is_nearer_the_ray_march_than_billboards(spread, ratio):
    """Where neighbours overlap in pairs the one segment held per pixel is nearly exact; in a dense clump
    (spread 2 m, radii 3-6 m), where many overlap one pixel, what is sent into the frame before the
    nearer ones arrive is ordered as billboards are, and the gain is small."""
    generator = np.random.default_rng(3)
    count = 40
    centres = generator.normal(0.0, spread, (count, 3)) + [0.0, 0.0, -100.0]
    colours = generator.uniform(0.1, 1.0, (count, 3))
    crowd = splats(centres, generator.uniform(3.0, 6.0, count), colours, generator.uniform(0.2, 0.9, count))
    reference = ray_marched(crowd, RAYS, BACKGROUND, steps=2048)
    volume_error = np.sqrt(np.mean((volume_blend(crowd, RAYS, BACKGROUND) - reference) ** 2))
    plain_error = np.sqrt(np.mean((plain_blend(crowd, RAYS, BACKGROUND) - reference) ** 2))
    assert volume_error < ratio * plain_error, (volume_error, plain_error)


def test_the_world_cuts_segments_where_billboards_are_cut_whole():
    """An opaque wall just behind a particle's centre: its billboard is drawn whole, its volume keeps the
    chord's front half (Yusov's soft intersection with the world); a wall in front hides both."""
    single = splats([[0.0, 0.0, -100.0]], [6.0], [[1.0, 1.0, 1.0]], [0.9])
    transparent = np.zeros((len(RAYS), 4))
    wall = 100.001 / -RAYS[:, 2]  # ray distance to the plane z = -100.001
    centre_pixel = (HEIGHT // 2) * WIDTH + WIDTH // 2
    optical_depth = particle_segments(single, 0, RAYS).optical_depth[centre_pixel]
    volume = volume_blend(single, RAYS, transparent, wall)
    np.testing.assert_allclose(volume, ray_marched(single, RAYS, transparent, wall), atol=1e-9)
    assert volume[centre_pixel, 3] == pytest.approx(-np.expm1(-optical_depth / 2), rel=1e-2)
    plain = plain_blend(single, RAYS, transparent, wall)
    assert plain[centre_pixel, 3] == pytest.approx(-np.expm1(-optical_depth))
    in_front = np.full(len(RAYS), 90.0)
    np.testing.assert_array_equal(volume_blend(single, RAYS, BACKGROUND, in_front), BACKGROUND)
    np.testing.assert_array_equal(plain_blend(single, RAYS, BACKGROUND, in_front), BACKGROUND)


@pytest.mark.parametrize(
    "centres, radii, opacities",
    [
        ([[0.0, 0.0, -100.0], [0.0, 0.0, -100.0]], [0.0, 0.0], [0.9, 0.9]),  # zero radius
        ([[0.0, 0.0, -100.0], [0.0, 0.0, -100.0]], [6.0, 6.0], [1.0, 1.0]),  # opacity 1: tau would be inf
        ([[0.0, 0.0, -100.0], [0.0, 0.0, -100.0]], [6.0, 1e-300], [1.0 - 1e-17, 1.0]),  # huge density
        ([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]], [6.0, 6.0], [0.9, 0.9]),  # at the eye and behind it
        ([[0.0, 0.0, -100.0], [1e6, 0.0, -100.0]], [6.0, 1e5], [0.0, 0.9]),  # invisible, grazing at the edge
    ],
)
def test_extremes_stay_finite(centres, radii, opacities):
    crowd = splats(centres, radii, [[1.0, 0.5, 0.2], [0.2, 0.5, 1.0]], opacities)
    for blend in (plain_blend, volume_blend, ray_marched):
        image = blend(crowd, RAYS, BACKGROUND)
        assert np.all(np.isfinite(image)), blend.__name__
        assert np.all(image >= 0.0) and np.all(image[:, 3] <= 1.0 + 1e-12), blend.__name__
    segments = particle_segments(crowd, 0, RAYS)
    assert np.all(segments.optical_depth <= MAX_OPTICAL_DEPTH)


def test_no_particles_leave_the_background():
    empty = splats(np.zeros((0, 3)), [], np.zeros((0, 3)), [])
    for blend in (plain_blend, volume_blend, ray_marched):
        np.testing.assert_array_equal(blend(empty, RAYS, BACKGROUND), BACKGROUND)


@pytest.mark.parametrize(
    "requested, compute, plain_only, expected",
    [
        ("plain", True, True, "plain"),
        ("volume", True, True, "volume"),
        ("volume", False, True, "plain"),  # no compute shaders: the fallback
        ("volume", True, False, "plain"),  # sprites or artist colours in the batch: billboards
    ],
)
def test_the_path_follows_the_setting_and_what_the_gl_can_do(requested, compute, plain_only, expected):
    assert blending_path(requested, compute_shaders=compute, plain_splats_only=plain_only) == expected


def test_screen_tiles_list_every_splat_where_it_draws_and_only_there_in_the_batch_order():
    """Every tile with a pixel a splat reaches lists it, and no tile more than two pixels from one (its disc,
    a pixel wider for rounding: not the corners of its square, which hold a quarter of its tiles)."""
    camera = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 50.0)
    width, height = 70, 45  # tiles that do not divide the screen
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, width / height)
    generator = np.random.default_rng(8)
    centres = generator.uniform([-60.0, -40.0, -120.0], [60.0, 40.0, -20.0], (50, 3))
    centres[0] = [0.0, 0.0, 5.0]  # behind the eye: in no tile
    radii = generator.uniform(1.0, 12.0, 50)
    tiles = screen_tiles(centres, radii, view, projection, (width, height), NEAR_PLANE_M)
    across, up = -(-width // TILE_PIXELS), -(-height // TILE_PIXELS)
    assert (tiles.across, tiles.up) == (across, up) and len(tiles.starts) == across * up + 1
    drawn = Splats(centres, radii, np.ones((50, 3)), np.ones(50), view[0, :3], view[1, :3])
    rays = pixel_rays(camera, width, height).reshape(height, width, 3)[::-1].reshape(-1, 3)  # rows bottom first
    listed_by_tile = [tiles.entries[tiles.starts[t] : tiles.starts[t + 1]] for t in range(tiles.count)]
    for position in range(50):
        reached = particle_segments(drawn, position, rays).optical_depth.reshape(height, width) > 0.0
        for row, column in zip(*np.nonzero(reached)):
            tile = (row // TILE_PIXELS) * tiles.across + column // TILE_PIXELS
            assert position in listed_by_tile[tile], (position, row, column)
        near_reached = np.zeros((up * TILE_PIXELS + 4, across * TILE_PIXELS + 4), dtype=bool)
        for dy, dx in np.ndindex(5, 5):  # two pixels around each pixel reached
            near_reached[dy : dy + height, dx : dx + width] |= reached
        near_reached = near_reached[2:-2, 2:-2].reshape(up, TILE_PIXELS, across, TILE_PIXELS).any(axis=(1, 3))
        listing = [t for t in range(tiles.count) if position in listed_by_tile[t]]
        assert all(near_reached.ravel()[listing]), position
    assert 0 not in tiles.entries
    listing = [tile for tile in range(tiles.count) if tiles.starts[tile + 1] > tiles.starts[tile]]
    assert list(tiles.occupied) == listing and len(listing) < tiles.count
    for tile in range(tiles.count):
        listed = tiles.entries[tiles.starts[tile] : tiles.starts[tile + 1]]
        assert np.all(np.diff(listed.astype(np.int64)) > 0)  # far to near, as the batch


def test_screen_tiles_of_no_splats_are_empty():
    size = (TILE_PIXELS, TILE_PIXELS)
    tiles = screen_tiles(np.zeros((0, 3)), np.zeros(0), np.eye(4), projection_matrix(60.0, 1.0), size, 0.1)
    assert tiles.count == 1 and list(tiles.starts) == [0, 0] and len(tiles.entries) == len(tiles.occupied) == 0


def test_window_depth_becomes_distance_along_each_ray():
    width, height = 8, 6
    view, projection = view_matrix(CAMERA), projection_matrix(CAMERA.fov_y_deg, width / height)
    rays = pixel_rays(CAMERA, width, height).reshape(-1, 3)
    points = 250.0 * rays  # every pixel sees something 250 m away
    clip = (projection @ view @ np.column_stack([points, np.ones(len(points))]).T).T
    window = 0.5 * clip[:, 2] / clip[:, 3] + 0.5
    np.testing.assert_allclose(ray_distances(np.append(window[:-1], 1.0), rays, view, projection)[:-1], 250.0)
    assert ray_distances(np.ones(1), rays[:1], view, projection)[0] == np.inf


def test_the_ray_march_in_tiles_is_the_whole_ray_march():
    camera = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 40.0)
    width, height = 37, 21
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, width / height)
    generator = np.random.default_rng(4)
    centres = generator.uniform([-40.0, -20.0, -100.0], [40.0, 20.0, -60.0], (30, 3))
    crowd = splats(centres, generator.uniform(3.0, 9.0, 30), generator.uniform(0.1, 1.0, (30, 3)), np.full(30, 0.8))
    rays = pixel_rays(camera, width, height).reshape(-1, 3)
    background = np.tile([0.2, 0.3, 0.5, 1.0], (len(rays), 1))
    opaque = np.full(len(rays), 85.0)
    tiles = screen_tiles(crowd.centres, crowd.radii, view, projection, (width, height), NEAR_PLANE_M)
    whole = ray_marched(crowd, rays, background, opaque, steps=64)
    np.testing.assert_allclose(ray_marched_in_tiles(crowd, rays, background, opaque, tiles, 64), whole, atol=1e-12)
