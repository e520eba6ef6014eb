"""The terrain's tiles (`cloudcore.world.terrain_tiles`): they cover the drawn square once, near the eye at the
heightfield's own resolution, their skirts close every gap between levels, and their count grows with the log
of the reach."""

import dataclasses
import itertools

import numpy as np
import pytest

from cloudcore.light.cloud_shadows import SLICES, light_space, sample_map
from cloudcore.model.scene import Camera, Terrain
from cloudcore.scenes.files import load_scene
from cloudcore.world import terrain_tiles
from cloudcore.world.camera import frustum_planes, projection_matrix, view_matrix
from cloudcore.world.terrain_tiles import (
    SKIRT_CELLS,
    SKIRT_SIDES,
    TILE_CELLS,
    TILE_FACES,
    TILE_VERTICES,
    TerrainTiles,
    leaf_tiles,
    skirted_sides,
    tile_errors_m,
    tile_faces,
    tile_frame,
    tile_meshes,
)
from tests.conftest import VALLEY

VALLEY_TERRAIN = load_scene(VALLEY).terrain
EYES = [(450.0, 330.0, 2900.0), (-2000.0, 1200.0, -500.0), (9000.0, 2500.0, 15000.0)]


def covering_counts(frame, tiles, samples=240):
    """How many tiles hold each of a grid of points over the drawn square (cell centres, off every edge)."""
    half = frame.half_side_m
    points = (np.arange(samples) + 0.5) / samples * 2 * half - half
    x0, z0, side = frame.corners(tiles)
    inside_x = (points[None, :] >= x0[:, None]) & (points[None, :] < (x0 + side)[:, None])
    inside_z = (points[None, :] >= z0[:, None]) & (points[None, :] < (z0 + side)[:, None])
    return np.einsum("tx,tz->xz", inside_x.astype(int), inside_z.astype(int))


@pytest.mark.parametrize("eye", EYES)
def test_the_tiles_cover_the_drawn_square_once(eye):
    frame = tile_frame(VALLEY_TERRAIN)
    assert np.all(covering_counts(frame, leaf_tiles(frame, eye)) == 1)


def test_the_ground_under_the_eye_is_at_the_heightfields_resolution():
    frame = tile_frame(VALLEY_TERRAIN)
    eye = EYES[0]
    tiles = leaf_tiles(frame, eye)
    x0, z0, side = frame.corners(tiles)
    under = (x0 <= eye[0]) & (eye[0] < x0 + side) & (z0 <= eye[2]) & (eye[2] < z0 + side)
    assert tiles[under, 0].tolist() == [0]
    assert side[under][0] / TILE_CELLS == pytest.approx(VALLEY_TERRAIN.size[0] / (VALLEY_TERRAIN.resolution - 1))
    # and farther, coarser
    assert tiles[:, 0].max() >= 5


def test_the_tiles_grow_with_the_log_of_the_reach_not_its_square():
    counts = []
    for reach in (6000.0, 12000.0, 24000.0, 48000.0):
        frame = tile_frame(dataclasses.replace(VALLEY_TERRAIN, reach=reach))
        counts.append(len(leaf_tiles(frame, EYES[0])))
    added = np.diff(counts)
    # each doubling quadruples the area but adds about one ring of tiles
    assert np.all(added > 0)
    assert added.max() <= 1.5 * added.min() + 8
    assert counts[-1] < 3 * counts[0]


def edge(grid, side):
    """The (n, 3) vertices along one side of a tile's (n, n, 3) grid (rows along z, columns along x)."""
    return {"low_z": grid[0], "high_z": grid[-1], "low_x": grid[:, 0], "high_x": grid[:, -1]}[side]


@pytest.mark.parametrize("eye", EYES[:2])
def test_the_skirts_close_every_gap_between_neighbouring_tiles(eye):
    """Along each edge two tiles share, the higher of the two edges hangs a skirt down past the other."""
    terrain = dataclasses.replace(VALLEY_TERRAIN, reach=12000.0)
    frame = tile_frame(terrain)
    tiles = leaf_tiles(frame, eye)
    positions, _ = tile_meshes(terrain, frame, tiles)
    n = TILE_CELLS + 1
    grids = positions[:, : n * n].reshape(len(tiles), n, n, 3)
    x0, z0, side = frame.corners(tiles)
    depth = SKIRT_CELLS * side / TILE_CELLS
    checked = 0
    for a, b in itertools.permutations(range(len(tiles)), 2):
        if side[a] > side[b]:
            continue  # a is the finer (or as fine) of the two
        for mine, theirs, touching in (
            ("high_x", "low_x", np.isclose(x0[a] + side[a], x0[b])),
            ("high_z", "low_z", np.isclose(z0[a] + side[a], z0[b])),
            ("low_x", "high_x", np.isclose(x0[a], x0[b] + side[b])),
            ("low_z", "high_z", np.isclose(z0[a], z0[b] + side[b])),
        ):
            along = 2 if mine.endswith("x") else 0
            fine, coarse = edge(grids[a], mine), edge(grids[b], theirs)
            lo, hi = max(fine[0, along], coarse[0, along]), min(fine[-1, along], coarse[-1, along])
            if not touching or hi <= lo:
                continue
            shared = (fine[:, along] >= lo - 1e-6) & (fine[:, along] <= hi + 1e-6)
            coarse_heights = np.interp(fine[shared, along], coarse[:, along], coarse[:, 1])
            fine_heights = fine[shared, 1]
            gap_above = fine_heights - coarse_heights  # the fine edge over the coarse one: its skirt hangs down
            assert np.all(gap_above <= depth[a] + 1e-6), (tiles[a], tiles[b], gap_above.max(), depth[a])
            assert np.all(-gap_above <= depth[b] + 1e-6), (tiles[a], tiles[b], (-gap_above).max(), depth[b])
            checked += 1
    assert checked > 20


@pytest.mark.parametrize("eye", EYES)
def test_a_skirt_is_left_out_only_where_a_neighbour_of_the_same_level_shares_the_edge_s_vertices(eye):
    """A side without its skirt (`skirted_sides`) has a tile of its own level across it whose edge vertices are its
    own, to the float32 the GPU draws (no gap to close); every other side (a coarser or finer neighbour, or the
    square's edge) keeps its skirt; and most sides need none."""
    terrain = dataclasses.replace(VALLEY_TERRAIN, reach=12000.0)
    frame = tile_frame(terrain)
    tiles = leaf_tiles(frame, eye)
    skirts = skirted_sides(tiles)
    positions, _ = tile_meshes(terrain, frame, tiles)
    n = TILE_CELLS + 1
    grids = positions[:, : n * n].reshape(len(tiles), n, n, 3).astype(np.float32)
    index = {tuple(tile): k for k, tile in enumerate(tiles.tolist())}
    mine_and_theirs = (("low_z", "high_z"), ("high_x", "low_x"), ("high_z", "low_z"), ("low_x", "high_x"))
    for k, tile in enumerate(tiles):
        for side, (mine, theirs) in enumerate(mine_and_theirs):
            across = index.get(tuple((tile + SKIRT_SIDES[side]).tolist()))
            assert skirts[k, side] == (across is None), (tile, side)
            if across is not None:
                np.testing.assert_array_equal(edge(grids[k], mine), edge(grids[across], theirs))
    assert skirts.mean() < 0.5


def test_each_side_s_skirt_is_a_run_of_its_own():
    """The skirt's triangles come side after side (`SKIRT_SIDES`' order), each side's hanging from that side's edge
    alone, so that the world pass draws a side's run or leaves it out."""
    n = TILE_CELLS + 1
    grid = np.arange(n * n).reshape(n, n)
    for stride in (1, 4):
        faces = tile_faces(stride)[2 * (TILE_CELLS // stride) ** 2 :]
        runs = faces.reshape(len(SKIRT_SIDES), -1, 3)
        for side, mine in enumerate(("low_z", "high_x", "high_z", "low_x")):
            on_the_grid = runs[side][runs[side] < n * n]
            assert set(on_the_grid.tolist()) <= set(edge(grid, mine).tolist()), (stride, side)


@pytest.mark.parametrize("stride", [1, 4])
def test_the_grids_face_up_and_the_skirts_out_of_their_tiles(stride):
    """Counter-clockwise (the world pass's front faces, its back faces culled): the grid's triangles seen from above,
    and each skirt's seen from outside its tile, where a gap at the tile's edge is seen from (from inside, the tile's
    own ground stands in front of its skirt)."""
    terrain = dataclasses.replace(VALLEY_TERRAIN, reach=12000.0)
    frame = tile_frame(terrain)
    tiles = leaf_tiles(frame, EYES[0])
    positions, _ = tile_meshes(terrain, frame, tiles)
    faces = tile_faces(stride)
    grid = 2 * (TILE_CELLS // stride) ** 2
    corners = positions[:, faces]  # (tiles, triangles, 3 corners, xyz)
    normals = np.cross(corners[:, :, 1] - corners[:, :, 0], corners[:, :, 2] - corners[:, :, 0])
    # (a tile pulled onto the drawn square's edge has cells of no width there)
    assert np.all(normals[:, :grid, 1] >= 0.0) and np.mean(normals[:, :grid, 1] > 0.0) > 0.9
    centres = positions[:, : (TILE_CELLS + 1) ** 2].mean(axis=1)
    outward = corners[:, grid:].mean(axis=2) - centres[:, None, :]
    hanging = np.linalg.norm(normals[:, grid:], axis=-1) > 0.0  # a skirt on the square's edge above 0 m has height
    along = np.einsum("tfk,tfk->tf", normals[:, grid:, [0, 2]], outward[:, :, [0, 2]])
    assert hanging.any() and np.all(along[hanging] > 0.0)


def test_a_tile_s_cells_come_row_after_row_their_two_triangles_together():
    """llvmpipe shades a draw's vertices through a small cache of the indices it last saw: a cell's two triangles
    drawn together reuse their vertices, and the grid's rows come in order."""
    n = TILE_CELLS + 1
    cells = TILE_FACES[: 2 * TILE_CELLS**2].reshape(TILE_CELLS**2, 2, 3)
    corner = (np.arange(TILE_CELLS)[:, None] * n + np.arange(TILE_CELLS)[None, :]).ravel()
    np.testing.assert_array_equal(cells.min(axis=(1, 2)), corner)
    assert all(len(set(cell.ravel().tolist())) == 4 for cell in cells)


def test_a_tile_reaches_a_distance_where_the_farthest_point_of_its_mesh_lies_beyond_it():
    """`reaching` picks the tiles whose vertices may lie past a distance from the eye (those drawn with the air to
    the planet's ground): every tile with a vertex past it, and none whose box lies wholly within it."""
    tiles = TerrainTiles(VALLEY_TERRAIN)
    eye = np.array(EYES[0])
    tiles.update(eye)
    vertices = tiles.positions.reshape(len(tiles.tiles), TILE_VERTICES, 3)
    farthest = np.linalg.norm(vertices - eye, axis=-1).max(axis=1)
    distance = float(np.median(farthest))
    reaching = tiles.reaching(eye, distance)
    assert np.all(reaching[farthest > distance])
    assert 0 < reaching.sum() < len(reaching)
    assert not tiles.reaching(eye, 2.0 * float(farthest.max())).any()


def test_moving_the_eye_meshes_only_the_new_tiles_and_a_still_eye_nothing(monkeypatch):
    meshed = []
    original = terrain_tiles.tile_meshes
    monkeypatch.setattr(
        terrain_tiles,
        "tile_meshes",
        lambda terrain, frame, tiles: meshed.append(len(tiles)) or original(terrain, frame, tiles),
    )
    terrain = dataclasses.replace(VALLEY_TERRAIN, seed=VALLEY_TERRAIN.seed + 1)  # no other test's tiles
    tiles = TerrainTiles(terrain)
    assert tiles.update(EYES[0])
    assert meshed == [len(tiles.tiles)]
    # a new light makes the world pass again, with tiles of its own: none is meshed again
    assert TerrainTiles(terrain).update(EYES[0]) and meshed == [len(tiles.tiles)]
    first = dict(zip(map(tuple, tiles.tiles.tolist()), tiles.positions.reshape(len(tiles.tiles), -1, 3)))
    assert not tiles.update(EYES[0])
    assert tiles.update((EYES[0][0], EYES[0][1], EYES[0][2] - 1500.0))
    again = dict(zip(map(tuple, tiles.tiles.tolist()), tiles.positions.reshape(len(tiles.tiles), -1, 3)))
    kept = set(first) & set(again)
    assert kept and len(kept) < len(again)
    assert meshed[1:] == [len(again) - len(kept)]
    for key in kept:
        np.testing.assert_array_equal(first[key], again[key])
    assert len(tiles.faces) == len(tiles.tiles) * len(TILE_FACES)
    assert tiles.faces.max() == len(tiles.positions) - 1


def test_tiles_out_of_view_are_left_out():
    tiles = TerrainTiles(VALLEY_TERRAIN)
    camera = Camera(EYES[0], (-250.0, 850.0, -600.0), 60.0)
    tiles.update(camera.position)
    in_view = tiles.in_view(frustum_planes(projection_matrix(60.0, 1.3) @ view_matrix(camera)))
    x0, z0, side = tiles.frame.corners(tiles.tiles)
    behind = z0 > camera.position[2] + 600.0  # the camera looks toward -z
    assert 0 < in_view.sum() < len(in_view)
    assert not np.any(in_view & behind)
    ahead = (x0 <= -250.0) & (-250.0 < x0 + side) & (z0 <= -600.0) & (-600.0 < z0 + side)
    assert np.all(in_view[ahead])


def test_a_patch_without_reach_is_drawn_to_its_edges_alone():
    terrain = Terrain(size=(6000.0, 6000.0), resolution=174)
    tiles = TerrainTiles(terrain)
    tiles.update(EYES[0])
    assert np.abs(tiles.positions[:, [0, 2]]).max() == pytest.approx(3000.0)
    assert np.all(np.isfinite(tiles.positions)) and np.all(np.isfinite(tiles.normals))
    np.testing.assert_allclose(np.linalg.norm(tiles.normals, axis=1), 1.0)


def test_the_tiles_left_off_the_clouds_map_read_none_of_it_and_the_map_s_middle_is_read():
    """Where `under_the_clouds_map` says no, the map as the GL side reads it (`sample_map`) gives no optical depth
    at any point of the tile, whatever the map holds: those tiles' pixels skip its reads and draw the same."""
    tiles = TerrainTiles(VALLEY_TERRAIN)
    tiles.update(EYES[0])
    centres = np.array([[0.0, 1800.0, 0.0], [1500.0, 2000.0, -2500.0], [-800.0, 1600.0, 1200.0]])
    radii = np.full(len(centres), 500.0)
    space = light_space(centres, radii, (0.4, 0.6, 0.3), 64)
    under = tiles.under_the_clouds_map(space)
    assert 0 < under.sum() < len(under)
    # a map dense everywhere: any read within reach of a texel would show
    values = np.full((SLICES, space.size[1], space.size[0]), 5.0)
    off = np.repeat(~under, TILE_VERTICES)
    assert np.all(sample_map(space, values, tiles.positions[off]) == 0.0)
    # and the tiles left in read it: some of their vertices lie under the clouds
    read = sample_map(space, values, tiles.positions).reshape(len(under), TILE_VERTICES) > 0.0
    assert np.any(read[under])


def test_a_tile_within_a_texel_of_the_clouds_map_reads_it_and_one_farther_does_not():
    """The map's bilinear read reaches a half texel past its edge (the border clear): a box there is under it."""
    space = light_space(np.zeros((1, 3)), np.array([500.0]), (0.4, 0.6, 0.3), 64)
    across = np.linspace(-2.0, 0.5, 26)
    x, y, s = across, np.full_like(across, 0.5 * space.size[1]), np.full_like(across, 4.0)
    right, up, forward = (np.asarray(v) for v in (space.right, space.up, space.forward))
    points = (
        (space.origin[0] + x[:, None] * space.texel_m) * right
        + (space.origin[1] + y[:, None] * space.texel_m) * up
        + (space.near_m + s[:, None] * space.slice_m) * forward
    )
    tiles = TerrainTiles(VALLEY_TERRAIN)
    tiles.boxes = np.stack([points, points], axis=1)  # a box a point
    under = tiles.under_the_clouds_map(space)
    read = sample_map(space, np.full((SLICES, space.size[1], space.size[0]), 5.0), points) > 0.0
    assert np.all(under[read]) and read.any()
    assert not np.any(under[across < -1.0])
    # in front of every slice, nothing is read
    tiles.boxes = np.stack([points, points], axis=1) - 4.5 * space.slice_m * forward
    assert not tiles.under_the_clouds_map(space).any()


@pytest.mark.parametrize("eye", EYES[:2])
def test_a_near_tile_is_left_coarse_only_where_its_ground_strays_less_than_the_angle_from_it(eye):
    tiles = TerrainTiles(VALLEY_TERRAIN)
    tiles.update(eye)
    frame = tiles.frame
    by_distance = leaf_tiles(frame, eye)
    assert np.all(covering_counts(frame, tiles.tiles) == 1)
    keys = {tuple(row) for row in by_distance.tolist()}
    kept_coarse = np.array([row for row in tiles.tiles.tolist() if tuple(row) not in keys])
    assert 0 < len(kept_coarse) and len(tiles.tiles) < len(by_distance)
    # each tile left coarser is one the distance alone would split, and its ground within the angle of it
    x0, z0, side = frame.corners(kept_coarse)
    dx = np.maximum.reduce([x0 - eye[0], np.zeros_like(x0), eye[0] - (x0 + side)])
    dz = np.maximum.reduce([z0 - eye[2], np.zeros_like(z0), eye[2] - (z0 + side)])
    distance = np.sqrt(dx * dx + dz * dz + max(eye[1] - frame.top_m, 0.0) ** 2)
    assert np.all(distance < terrain_tiles.SPLIT_DISTANCE * side)
    errors = tile_errors_m(VALLEY_TERRAIN, frame, kept_coarse)
    assert np.all(errors <= terrain_tiles.SPLIT_ERROR_RAD * distance)


def test_a_tiles_error_is_none_over_a_plane_and_the_grounds_largest_departure_from_its_triangles():
    terrain = dataclasses.replace(VALLEY_TERRAIN, relief=0.0)
    frame = tile_frame(terrain)
    middle = 2 ** (frame.root_level - 2) // 2  # a tile of level 2 at the origin, within the drawn square
    tile = np.array([[2, middle, middle - 1]])
    x0, z0, side = (float(v[0]) for v in frame.corners(tile))
    # the ground's heights at the grid's vertices and halfway along each cell's diagonal
    fine = np.linspace(0.0, side, 2 * TILE_CELLS + 1)
    heights = terrain_tiles.height_at(terrain, x0 + fine[None, :], z0 + fine[:, None])
    vertices = heights[::2, ::2]
    diagonal = 0.5 * (vertices[1:, :-1] + vertices[:-1, 1:])  # down-across, the two triangles' shared edge
    assert tile_errors_m(terrain, frame, tile)[0] >= np.abs(heights[1::2, 1::2] - diagonal).max() - 1e-9
    flat = Terrain(size=(6000.0, 6000.0), resolution=174, height=0.0)
    assert tile_errors_m(flat, tile_frame(flat), np.array([[1, 2, 2], [0, 3, 4]])).max() == pytest.approx(0.0, abs=1e-9)
