"""The clouds' shadow on the ground baked into a texture over the ground: one fetch a terrain pixel.

The clouds' transmittance map (`cloudcore.light.cloud_shadows`) is read by each terrain pixel at its place along
the sun: two fetches of eight slices and an exponential, which cost llvmpipe about a third of the terrain's draw.
The ground is a heightfield, so each point of it over the ground's plane has one height, and the share of the sun
that reaches it can be baked once for a map that stays (and for the tiles an eye's move brings in) into a texture
over the ground's plane, which the terrain's pixels then read with one fetch (`BakePlan`; docs/performance.md,
"The clouds' shadow baked on the ground").

The texture's axes are level: `along`, the map's `right` laid on the ground, and `across`, a quarter turn from it
about the world's up.  Its texels are `TEXELS_PER_MAP_TEXEL` times as fine on the ground as the map's (a map's
texel, seen on level ground, stretches along the sun's azimuth as the sun sinks), and it covers the map's
footprint on the ground between the terrain's lowest and highest points, a texel of the map beyond its border
included (there the map reads 1), within the square the terrain is drawn to.  The map's `right` is level
(`light_basis`) but for a sun at the zenith.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.light.cloud_shadows import LightSpace

#: the texture's texels along each level axis for one of the map's: finer than the map, so that its bilinear read
#: of the share follows the map's read of the optical depth (the share's exponential) across a shadow's edge; 3
#: costs the bake twice as much for little (docs/performance.md, "The clouds' shadow baked on the ground")
TEXELS_PER_MAP_TEXEL = 2
#: the most texels along either side of the baked texture: a map seen from a low sun spreads far along the ground,
#: and its texels there are as long (the baked texels grow to fit)
MOST_TEXELS = 2048
#: the least sine of the sun's elevation for which the map's footprint bounds the texture: a sun at the horizon lays
#: it out to infinity (the texture then covers the terrain's whole square)
LEAST_SUN_SINE = 1e-3


@dataclass(frozen=True)
class GroundShadowFrame:
    """Where the baked texture lies on the ground: a point's level coordinates (`along`, `across`) less `origin`,
    over `texel_m`, are its texel coordinates (texel i spans [i, i + 1))."""

    along: tuple[float, float, float]
    across: tuple[float, float, float]
    origin: tuple[float, float]
    texel_m: tuple[float, float]
    size: tuple[int, int]  # texels (along, across)

    def texel_coordinates(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(i, j) texel coordinates of world `points` (n, 3); their heights do not matter."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        i = (points @ np.asarray(self.along) - self.origin[0]) / self.texel_m[0]
        j = (points @ np.asarray(self.across) - self.origin[1]) / self.texel_m[1]
        return i, j

    def texel_centres(self) -> np.ndarray:
        """(across, along, 2): the (x, z) of every texel's centre, row j, column i."""
        i, j = np.meshgrid(np.arange(self.size[0]) + 0.5, np.arange(self.size[1]) + 0.5)
        along = self.origin[0] + i * self.texel_m[0]
        across = self.origin[1] + j * self.texel_m[1]
        xz = np.asarray(self.along)[[0, 2]] * along[..., None] + np.asarray(self.across)[[0, 2]] * across[..., None]
        return xz

    def world_to_texture(self) -> np.ndarray:
        """4x4: world (x, y, z, 1) to (u, v, 0, 1), u and v texture coordinates in [0, 1] over the texture."""
        matrix = np.zeros((4, 4))
        for row, (axis, origin, texel_m, texels) in enumerate(
            zip((self.along, self.across), self.origin, self.texel_m, self.size, strict=True)
        ):
            matrix[row, :3] = np.asarray(axis) / (texel_m * texels)
            matrix[row, 3] = -origin / (texel_m * texels)
        matrix[3, 3] = 1.0
        return matrix


def ground_shadow_frame(space: LightSpace, lowest_m: float, highest_m: float, half_side_m: float) -> GroundShadowFrame:
    """The frame of the texture that holds the clouds' shadow of the map of light `space` on the ground between the
    heights `lowest_m` and `highest_m`, within the square of half side `half_side_m` about the origin that the
    terrain is drawn to (all of it for a sun within `LEAST_SUN_SINE` of the horizon)."""
    right, up, forward = (np.asarray(v, dtype=np.float64) for v in (space.right, space.up, space.forward))
    level_right = np.array([right[0], 0.0, right[2]])
    along = level_right / np.linalg.norm(level_right)
    across = np.array([-along[2], 0.0, along[0]])
    axes = np.stack([along, across], axis=1)
    square = half_side_m * np.array([[x, 0.0, z] for x in (-1.0, 1.0) for z in (-1.0, 1.0)]) @ axes
    low, high = square.min(axis=0), square.max(axis=0)
    if -forward[1] >= LEAST_SUN_SINE:
        # the map's corners a texel beyond its border, as lines along the light, met by the lowest and highest
        # ground
        width, height = space.size
        corners = np.array([[x, y] for x in (-1.0, width + 1.0) for y in (-1.0, height + 1.0)])
        in_plane = (np.asarray(space.origin) + corners * space.texel_m) @ np.stack([right, up])
        reach = np.concatenate([(level - in_plane[:, 1]) / forward[1] for level in (lowest_m, highest_m)])
        footprint = (np.concatenate([in_plane, in_plane]) + reach[:, None] * forward) @ axes
        low, high = np.maximum(low, footprint.min(axis=0)), np.minimum(high, footprint.max(axis=0))
        high = np.maximum(high, low)
    # the map's texels on level ground: a step along a level axis moves (right, up) by the map's metres per metre
    per_metre = np.abs(np.stack([right, up]) @ axes).max(axis=0)
    texel_m = space.texel_m / np.maximum(per_metre, 1e-12) / TEXELS_PER_MAP_TEXEL
    texel_m = np.maximum(texel_m, (high - low) / MOST_TEXELS)
    size = np.maximum(np.ceil((high - low) / texel_m).astype(int), 1)
    return GroundShadowFrame(
        tuple(float(v) for v in along),
        tuple(float(v) for v in across),
        (float(low[0]), float(low[1])),
        (float(texel_m[0]), float(texel_m[1])),
        (int(size[0]), int(size[1])),
    )


def tile_keys(tiles) -> np.ndarray:
    """(n,) int64: one number for each tile (rows level, i, j: `cloudcore.world.terrain_tiles`), to compare sets."""
    tiles = np.asarray(tiles, dtype=np.int64).reshape(-1, 3)
    return (tiles[:, 0] << 48) | (tiles[:, 1] << 24) | tiles[:, 2]


def steady_map(preview: bool, field: bool, moving: bool, forming: bool) -> bool:
    """Whether the clouds' map is one a frame keeps: not a dragged slider's look (`preview`), a cloud field's
    (`field`: its clouds' blend weights change as the eye flies), the map of clouds the wind carries (`moving`) or
    of clouds that form or dissipate (`forming`), all made again, or moved, nearly every frame.  A steady map is
    baked on the ground; the others are read per pixel, as their bake would cost more than their reads save
    (docs/performance.md, "The clouds' shadow baked on the ground")."""
    return not (preview or field or moving or forming)


@dataclass(frozen=True)
class BakeStep:
    """What a frame does with the ground's shadow: whether the tiles under the clouds' map read the baked texture
    (else the map, per pixel), whether it is baked afresh (cleared), and which of the tiles given are baked."""

    read_baked: bool
    afresh: bool
    tiles: np.ndarray  # indices into the tiles given to `BakePlan.step`


class BakePlan:
    """When the shadow on the ground is baked, frame by frame: a steady map (`steady_map`) on its first frame, then
    kept; a new set of tiles bakes only the tiles it did not hold, over the ground of those it drops (the tiles
    cover the square once).  docs/performance.md, "The clouds' shadow baked on the ground"."""

    def __init__(self):
        self._baked_map = None  # the map the texture holds
        self._baked_tiles = np.zeros(0, dtype=np.int64)  # the tiles it holds (`tile_keys`)

    def step(self, map_key, keys: np.ndarray, steady: bool) -> BakeStep:
        """The step of a frame whose map is `map_key` (any comparable value naming the map and its place), `steady`
        or not, and whose tiles under the map are `keys` (`tile_keys`)."""
        keys = np.asarray(keys, dtype=np.int64)
        if not steady:
            return BakeStep(False, False, np.zeros(0, dtype=np.int64))
        afresh = map_key != self._baked_map
        missing = np.ones(len(keys), dtype=bool) if afresh else ~np.isin(keys, self._baked_tiles)
        self._baked_map, self._baked_tiles = map_key, keys
        return BakeStep(True, afresh, np.flatnonzero(missing))
