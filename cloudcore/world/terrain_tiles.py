"""The heightfield drawn as tiles whose cells grow with their distance from the eye: a quadtree chosen per eye.

A tile is a square of `TILE_CELLS` x `TILE_CELLS` cells.  The finest tiles' cells are the heightfield's own
spacing (`Terrain.size` over its samples, `terrain.finest_cell_m`: the ground near the eye at full resolution),
each level's cells twice its children's.  The root, centred on the origin, covers the drawn square (its half
side the larger of `Terrain.reach` and the patch's half sides; vertices past it are pulled onto its edge), and a
tile is split while the eye is nearer to it than `SPLIT_DISTANCE` of its sides and its ground strays from its
triangles by more than `SPLIT_ERROR_RAD` seen from the eye.  A cell then spans a near constant angle
from the eye, and the tiles' count grows with the log of the reach, not its square.

Neighbouring tiles of different levels meet along an edge that the coarser samples half as often.  Each tile
hangs a skirt from its edges, `SKIRT_CELLS` of its cells deep, which closes the gap between the two
(tests/unit/world/test_terrain_tiles.py checks it), but not below the origin's level (nor its lowest sample), where
the planet's ground drawn past the square lies; on the square's edge, where no tile neighbours it, down to that
level.
Why tiles: docs/performance.md, "The world pass: where its time goes".
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from cloudcore.model.scene import Terrain
from cloudcore.world.terrain import finest_cell_m, height_at, highest_ground_m

#: cells along a tile's side
TILE_CELLS = 16
#: a tile is split while the eye is nearer to it than this many of its sides
SPLIT_DISTANCE = 1.0
#: a tile near enough to split is split only while its height error (`tile_errors_m`) over the eye's distance
#: exceeds this angle: about 2 pixels of the default view at 880x680 (60 degrees over 680 rows).  The valley's
#: floor near the eye, whose finest tiles add little, is drawn coarser; its hills as before
#: (docs/performance.md, "The terrain's pixels off the clouds' map")
SPLIT_ERROR_RAD = 0.003
#: the coarsest level a near tile is left at for its small error (cells 2 finest cells wide): its light, the air
#: and the light shafts' share are read per vertex, which near the eye must stay close together (a plain's near
#: ground left at level 2 and coarser stepped the picture as the eye moved: tests/render/test_render_cloud_field.py)
COARSEST_NEAR_LEVEL = 1
#: height samples a cell along each side when a tile's error is measured
ERROR_SAMPLES = 4
#: a skirt's depth in its tile's cells: deeper than a coarser neighbour's edge strays from the tile's
SKIRT_CELLS = 2.0

_SIDE_VERTICES = TILE_CELLS + 1


@dataclass(frozen=True)
class TileFrame:
    """Where one terrain's tiles lie: the finest cell, the root's level, the drawn square and the highest ground."""

    cell_m: float
    root_level: int
    half_side_m: float
    top_m: float

    def sides(self, levels: np.ndarray) -> np.ndarray:
        """The side in metres of tiles of `levels`."""
        return TILE_CELLS * self.cell_m * np.exp2(np.asarray(levels, dtype=np.float64))

    def corners(self, tiles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, z) of the low corner and the side of each tile (rows level, i along x, j along z)."""
        tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 3)
        side = self.sides(tiles[:, 0])
        root_half = 0.5 * float(self.sides(self.root_level))
        return tiles[:, 1] * side - root_half, tiles[:, 2] * side - root_half, side


def tile_frame(terrain: Terrain) -> TileFrame:
    """The frame of `terrain`'s tiles: the finest cell the heightfield's spacing, the root just covering the
    drawn square."""
    cell = finest_cell_m(terrain)
    half = max(terrain.reach, 0.5 * max(terrain.size))
    root_level = max(0, math.ceil(math.log2(2.0 * half / (TILE_CELLS * cell))))
    return TileFrame(cell, root_level, half, highest_ground_m(terrain))


def tile_errors_m(terrain: Terrain, frame: TileFrame, tiles: np.ndarray) -> np.ndarray:
    """(n,) the largest height difference (m) between `terrain` and the grid of each of `tiles` (level, i, j rows)
    over it, `ERROR_SAMPLES` samples a cell along each side (`tile_faces`' cells split along their down-across
    diagonal)."""
    tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 3)
    x0, z0, side = frame.corners(tiles)
    samples = TILE_CELLS * ERROR_SAMPLES
    along = np.arange(samples + 1) / samples
    half = frame.half_side_m
    xs = np.clip(x0[:, None] + along[None, :] * side[:, None], -half, half)
    zs = np.clip(z0[:, None] + along[None, :] * side[:, None], -half, half)
    heights = height_at(terrain, xs[:, None, :], zs[:, :, None])  # (n, along z, along x)
    vertices = heights[:, ::ERROR_SAMPLES, ::ERROR_SAMPLES]
    cell = np.minimum(np.arange(samples + 1) // ERROR_SAMPLES, TILE_CELLS - 1)
    inside = np.arange(samples + 1) / ERROR_SAMPLES - cell
    u, v, column, row = inside[None, None, :], inside[None, :, None], cell[None, :], cell[:, None]
    h00, h01 = vertices[:, row, column], vertices[:, row, column + 1]
    h10, h11 = vertices[:, row + 1, column], vertices[:, row + 1, column + 1]
    first = h00 + u * (h01 - h00) + v * (h10 - h00)
    second = h11 + (1.0 - u) * (h10 - h11) + (1.0 - v) * (h01 - h11)
    return np.abs(np.where(u + v <= 1.0, first, second) - heights).max(axis=(1, 2))


def leaf_tiles(frame: TileFrame, eye, errors_m=None) -> np.ndarray:
    """(n, 3) int64 rows (level, i, j) of the tiles drawn for an eye at `eye` (x, y, z), sorted: split from the
    root down while the eye is nearer than `SPLIT_DISTANCE` sides and, where `errors_m(tiles)` gives the tiles'
    height errors (`tile_errors_m`), for tiles of `COARSEST_NEAR_LEVEL` or finer, while that error seen from the eye
    exceeds `SPLIT_ERROR_RAD`; tiles wholly off the drawn square dropped."""
    ex, ey, ez = (float(v) for v in eye)
    # above the highest ground the eye's height counts toward its distance; below, the ground may be level with it
    above = max(ey - frame.top_m, 0.0)
    half = frame.half_side_m
    tiles = np.array([[frame.root_level, 0, 0]], dtype=np.int64)
    leaves = []
    for level in range(frame.root_level, -1, -1):
        x0, z0, side = frame.corners(tiles)
        on_square = (x0 < half) & (x0 + side > -half) & (z0 < half) & (z0 + side > -half)
        tiles, x0, z0, side = tiles[on_square], x0[on_square], z0[on_square], side[on_square]
        if level == 0:
            leaves.append(tiles)
            break
        dx = np.maximum.reduce([x0 - ex, np.zeros_like(x0), ex - (x0 + side)])
        dz = np.maximum.reduce([z0 - ez, np.zeros_like(z0), ez - (z0 + side)])
        distance = np.sqrt(dx * dx + dz * dz + above * above)
        split = distance < SPLIT_DISTANCE * side
        if errors_m is not None and level <= COARSEST_NEAR_LEVEL and split.any():
            split[split] = errors_m(tiles[split]) > SPLIT_ERROR_RAD * distance[split]
        leaves.append(tiles[~split])
        parents = tiles[split]
        quarter = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], dtype=np.int64)
        children = 2 * parents[:, None, 1:] + quarter[None, :, :]
        tiles = np.concatenate([np.full((len(parents), 4, 1), level - 1, dtype=np.int64), children], axis=2).reshape(
            -1, 3
        )
    found = np.concatenate(leaves)
    return found[np.lexsort((found[:, 2], found[:, 1], found[:, 0]))]


def _perimeter() -> np.ndarray:
    """A tile's edge vertices, once each, in order around it (indices into its grid, row z, column x)."""
    last = TILE_CELLS
    grid = np.arange(_SIDE_VERTICES * _SIDE_VERTICES).reshape(_SIDE_VERTICES, _SIDE_VERTICES)
    return np.concatenate([grid[0, :last], grid[:last, last], grid[last, last:0:-1], grid[last:0:-1, 0]])


_PERIMETER = _perimeter()
#: vertices of one tile: its grid, then its skirt's lower edge
TILE_VERTICES = _SIDE_VERTICES * _SIDE_VERTICES + len(_PERIMETER)


def tile_faces(stride: int = 1) -> np.ndarray:
    """One tile's triangles: its grid's (counter-clockwise from above), then its skirt's (counter-clockwise seen
    from outside the tile); with a `stride` (a divisor of `TILE_CELLS`), those of the grid of every `stride`-th
    vertex, a coarser surface over the same vertices.

    The grid's cells come row after row, a cell's two triangles together: llvmpipe shades a draw's vertices through
    a small cache of the indices it last saw, and a cell's second triangles drawn after all the firsts came back to
    vertices it had let go (docs/performance.md, "The terrain's triangles on llvmpipe")."""
    n = _SIDE_VERTICES
    i = np.arange(0, TILE_CELLS, stride)
    corner = (i[:, None] * n + i[None, :]).ravel()
    across, down = stride, stride * n
    grid = np.stack(
        [
            np.stack([corner, corner + down, corner + across], axis=1),
            np.stack([corner + across, corner + down, corner + down + across], axis=1),
        ],
        axis=1,
    ).reshape(-1, 3)
    kept = np.arange(0, len(_PERIMETER), stride)
    top, following = _PERIMETER[kept], np.roll(_PERIMETER[kept], -1)
    bottom = n * n + kept
    bottom_following = np.roll(bottom, -1)
    # a quad's two triangles together, the quads in the perimeter's order: each side's skirt a run of its own
    # (`SKIRT_SIDES`), which the world pass draws or leaves out (`skirted_sides`).  Facing out of the tile: a gap
    # at the tile's edge is seen from the neighbour's side, and from inside the tile its own ground stands in front
    # of its skirt, so the world pass culls the skirts' back faces as the grids'
    skirt = np.stack(
        [np.stack([top, following, bottom], axis=1), np.stack([following, bottom_following, bottom], axis=1)], axis=1
    ).reshape(-1, 3)
    return np.concatenate([grid, skirt])


TILE_FACES = tile_faces()


def grid_face_count(stride: int = 1) -> int:
    """How many of `tile_faces(stride)`'s triangles are its grid's (the first), the rest its skirt's."""
    return 2 * (TILE_CELLS // stride) ** 2


#: a tile's sides in the order of its skirt's runs of triangles (`tile_faces`), as the (level, i, j) step to the
#: neighbour of the same level across each: low z, high x, high z, low x
SKIRT_SIDES = np.array([[0, 0, -1], [0, 1, 0], [0, 0, 1], [0, -1, 0]], dtype=np.int64)


def skirted_sides(tiles: np.ndarray) -> np.ndarray:
    """(n, 4) bool, per tile of `tiles` (`leaf_tiles`' rows) and side (`SKIRT_SIDES`): whether its skirt is needed
    there: where the neighbour across is not a tile of its own level (a coarser or finer one, whose edge samples the
    ground at other points, or none: the square's edge, where the skirt is the terrain's base).  Two tiles of one
    level share their edge's vertices, so no gap opens between them; their skirts, hanging below the ground, were
    hidden and cost llvmpipe their triangles (docs/performance.md, "The world pass within its budget")."""
    tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 3)
    neighbours = tiles[:, None, :] + SKIRT_SIDES[None, :, :]
    # a key per (level, i, j): i and j lie within [-1, 2^(root level)] (off the square by one at most)
    span = int(np.abs(neighbours[..., 1:]).max(initial=0)) + 2

    def keys(rows: np.ndarray) -> np.ndarray:
        return (rows[..., 0] * span + rows[..., 1] + 1) * span + rows[..., 2] + 1

    return ~np.isin(keys(neighbours), keys(tiles))


def tile_meshes(terrain: Terrain, frame: TileFrame, tiles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions and unit normals (T, TILE_VERTICES, 3) of `tiles`: each tile's grid, then its skirt's lower
    edge (the normals of the edge above it).  Normals by central differences over the tile's own cells, so a
    coarse tile is lit as the ground it stands for, smoothed."""
    tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 3)
    steps = np.arange(-1, _SIDE_VERTICES + 1)  # one cell beyond each edge, for the differences
    half = frame.half_side_m
    # in whole finest cells from the root's low corner, so that two tiles place the vertices they share on the same
    # float64 (`skirted_sides` leaves out the skirt between two tiles of a level)
    cells = np.exp2(tiles[:, 0:1]).astype(np.int64)
    root_half = 0.5 * float(frame.sides(frame.root_level))
    xs, zs = (
        np.clip((tiles[:, axis : axis + 1] * TILE_CELLS + steps) * cells * frame.cell_m - root_half, -half, half)
        for axis in (1, 2)
    )
    x = np.broadcast_to(xs[:, None, :], (len(xs), len(steps), len(steps)))
    z = np.broadcast_to(zs[:, :, None], x.shape)
    heights = height_at(terrain, x, z)
    # differences over the samples' own spacing: pulled onto the drawn square's edge, two may coincide
    run_x = xs[:, None, 2:] - xs[:, None, :-2]
    run_z = zs[:, 2:, None] - zs[:, :-2, None]
    slope_x = np.divide(
        heights[:, 1:-1, 2:] - heights[:, 1:-1, :-2], run_x, out=np.zeros(heights[:, 1:-1, 1:-1].shape), where=run_x > 0
    )
    slope_z = np.divide(
        heights[:, 2:, 1:-1] - heights[:, :-2, 1:-1], run_z, out=np.zeros(slope_x.shape), where=run_z > 0
    )
    normals = np.stack([-slope_x, np.ones_like(slope_x), -slope_z], axis=-1)
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    grid = np.stack([x[:, 1:-1, 1:-1], heights[:, 1:-1, 1:-1], z[:, 1:-1, 1:-1]], axis=-1)
    grid = grid.reshape(len(xs), -1, 3)
    normals = normals.reshape(len(xs), -1, 3)
    skirt = grid[:, _PERIMETER].copy()
    # no skirt hangs below the level of the scene's origin, where the planet's ground drawn past the square lies
    # (`cloudcore.light.far_ground`), nor below the tile's lowest sample: seen from outside the square, under the
    # terrain's edge, a skirt hung lower stood in front of that ground; a neighbour's edge, between samples of the
    # same heights, lies no lower.  On the square's edge, which no tile neighbours, the skirt is a wall down to
    # that level, the terrain's base
    top = skirt[:, :, 1]
    lowest = np.minimum(heights[:, 1:-1, 1:-1].min(axis=(1, 2)), 0.0)[:, None]
    hung = np.maximum(top - SKIRT_CELLS * (cells * frame.cell_m), lowest)
    on_edge = np.maximum(np.abs(skirt[:, :, 0]), np.abs(skirt[:, :, 2])) >= half
    skirt[:, :, 1] = np.where(on_edge, np.minimum(top, 0.0), np.minimum(hung, top))
    return np.concatenate([grid, skirt], axis=1), np.concatenate([normals, normals[:, _PERIMETER]], axis=1)


@functools.lru_cache(maxsize=2)
def _meshes_of(terrain: Terrain) -> dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray]]:
    """The meshes of `terrain`'s tiles drawn last, by tile: shared by its `TerrainTiles`, so that a new light,
    which makes the world pass again (every look of a dragged time-of-day slider), meshes no tile again."""
    return {}


@functools.lru_cache(maxsize=2)
def _errors_of(terrain: Terrain) -> dict[tuple[int, int, int], float]:
    """The height errors (`tile_errors_m`) of `terrain`'s tiles weighed for a split so far, by tile: a tile's
    error is the ground's, measured once."""
    return {}


class TerrainTiles:
    """The tiles drawn for the last eye and their meshes, kept from frame to frame: `update` meshes only the
    tiles the eye's move brings in."""

    def __init__(self, terrain: Terrain):
        self.terrain = terrain
        self.frame = tile_frame(terrain)
        self.tiles = np.zeros((0, 3), dtype=np.int64)
        self._meshes = _meshes_of(terrain)
        self.positions = np.zeros((0, 3))
        self.normals = np.zeros((0, 3))
        self.faces = np.zeros((0, 3), dtype=np.int64)
        #: per tile, the (low, high) corners of the box around its mesh, skirt and all
        self.boxes = np.zeros((0, 2, 3))
        #: per tile and side (`SKIRT_SIDES`), whether its skirt is drawn (`skirted_sides`)
        self.skirts = np.zeros((0, 4), dtype=bool)

    def update(self, eye) -> bool:
        """Choose the tiles for `eye`; whether they changed (then `positions`, `normals`, `faces` are new)."""
        tiles = leaf_tiles(self.frame, eye, self._errors_m)
        if np.array_equal(tiles, self.tiles):
            return False
        keys = list(map(tuple, tiles.tolist()))
        missing = [index for index, key in enumerate(keys) if key not in self._meshes]
        held = {key: self._meshes[key] for key in keys if key in self._meshes}
        if missing:
            positions, normals = tile_meshes(self.terrain, self.frame, tiles[missing])
            held.update({keys[index]: pair for index, pair in zip(missing, zip(positions, normals))})
        # the tiles left behind are dropped: a cache of what is drawn
        self._meshes.clear()
        self._meshes.update(held)
        self.tiles = tiles
        self.positions = np.concatenate([held[key][0] for key in keys])
        self.normals = np.concatenate([held[key][1] for key in keys])
        offsets = TILE_VERTICES * np.arange(len(keys), dtype=np.int64)
        self.faces = (TILE_FACES[None, :, :] + offsets[:, None, None]).reshape(-1, 3)
        tile_positions = self.positions.reshape(len(keys), TILE_VERTICES, 3)
        self.boxes = np.stack([tile_positions.min(axis=1), tile_positions.max(axis=1)], axis=1)
        self.skirts = skirted_sides(tiles)
        return True

    def _errors_m(self, tiles: np.ndarray) -> np.ndarray:
        """`tile_errors_m` of `tiles`, those measured before not measured again."""
        known = _errors_of(self.terrain)
        keys = list(map(tuple, tiles.tolist()))
        missing = [index for index, key in enumerate(keys) if key not in known]
        if missing:
            known.update(
                zip((keys[index] for index in missing), tile_errors_m(self.terrain, self.frame, tiles[missing]))
            )
        return np.array([known[key] for key in keys])

    def under_the_clouds_map(self, space) -> np.ndarray:
        """(tiles,) bool: whether the clouds' transmittance map of light space `space` (`cloud_shadows.LightSpace`)
        may dim the sun on any point of each tile's box.  A point off the map across the light (its texels' border
        is clear, and the bilinear read takes it a half texel in: one texel is left) or in front of every slice
        (slice coordinate 0 or less) is lit whole, so its pixels need not read the map; the map's coordinates are
        affine in the world's, so a box's corners bound them.  The far tiles are mostly off the map and their pixels
        skip its reads (docs/performance.md, "The terrain's pixels off the clouds' map")."""
        corners = np.stack(
            [
                np.where(np.array([k & 1, k & 2, k & 4], dtype=bool), self.boxes[:, 1], self.boxes[:, 0])
                for k in range(8)
            ],
            axis=1,
        )
        x, y, s = (c.reshape(-1, 8) for c in space.texel_coordinates(corners.reshape(-1, 3)))
        width, height = space.size
        across = (x.max(axis=1) > -1.0) & (x.min(axis=1) < width + 1.0)
        up = (y.max(axis=1) > -1.0) & (y.min(axis=1) < height + 1.0)
        return across & up & (s.max(axis=1) > 0.0)

    def reaching(self, eye, distance_m: float) -> np.ndarray:
        """(tiles,) bool: whether any point of each tile's box lies farther than `distance_m` from `eye`: its box's
        corner farthest from the eye along each axis."""
        farthest = np.maximum(np.abs(self.boxes[:, 0] - eye), np.abs(self.boxes[:, 1] - eye))
        return np.linalg.norm(farthest, axis=1) > distance_m

    def in_view(self, planes: np.ndarray) -> np.ndarray:
        """(tiles,) bool: whether each tile's box meets the view volume of `planes` (`camera.frustum_planes`):
        for each plane the box's corner farthest along its normal is tested."""
        planes = np.asarray(planes, dtype=np.float64)
        farthest = np.where(planes[None, :, :3] > 0.0, self.boxes[:, 1:2, :], self.boxes[:, 0:1, :])
        return np.all(np.einsum("tpk,pk->tp", farthest, planes[:, :3]) + planes[:, 3] >= 0.0, axis=1)
