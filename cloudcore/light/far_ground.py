"""The planet's ground past a terrain's drawn square, to the horizon: one colour, lit as the terrain is.

The terrain is drawn to its square (`terrain_tiles`, at most `reach` from the origin, as far as the air's
volume goes); past it the sky's rays below the horizon meet the planet's ground, which the sky draws as the air's
light in front of it plus its colour through the air (`SkyBackground.radiance`, shaders/sky.frag.glsl; Hillaire's
sky view with the ground, his `MultipleScattering` ground term, lit as our terrain rather than by the sun alone).
Its colour is the terrain's at the square's edge on level ground, lit by the terrain's own light (the sun's beam,
the sky's dome, the floor: `TerrainLight`), so that the terrain's edge and the ground past it differ only by
what the air's volume and the sky's table differ by at that distance (docs/atmosphere.md, "The ground past the
terrain").  The clouds shadow its sun's part (`far_ground_sun`) where the map of their shadows reaches past the
terrain (a cloud field's rings do), read on the level ground at its edge's height (`far_ground_level`): the
terrain's shadows go on across its edge (docs/atmosphere.md, "The far ground's cloud shadows").
"""

from __future__ import annotations

import numpy as np

from cloudcore.atmosphere.geometry import distance_to_ground
from cloudcore.light.cloud_shadows import LightSpace
from cloudcore.light.terrain_light import TerrainLight
from cloudcore.model.scene import Terrain
from cloudcore.world.terrain import ground_colours, height_at
from cloudcore.world.terrain_tiles import tile_frame

#: points along each side of the drawn square whose ground colours are averaged into the far ground's
EDGE_SAMPLES = 64
#: screen pixels between the rays `far_ground_box` tests, each way
BOX_STEP = 16
#: the share of the distance to the square's edge from which a ray's ground counts as past it: room for the float32
#: distance the shader takes against this float64 one
_EDGE_MARGIN = 0.95


def _edge_points(terrain: Terrain) -> np.ndarray:
    """(4 EDGE_SAMPLES, 3): points along the edge of the square the terrain's tiles are drawn to, at its heights."""
    half = tile_frame(terrain).half_side_m
    along = np.linspace(-half, half, EDGE_SAMPLES)
    ends = np.full(EDGE_SAMPLES, half)
    x = np.concatenate([along, along, -ends, ends])
    z = np.concatenate([-ends, ends, along, along])
    return np.stack([x, height_at(terrain, x, z), z], axis=1)


def edge_colour(terrain: Terrain) -> np.ndarray:
    """(3,) linear RGB: the mean ground colour (`ground_colours`, by height, level) along the edge of the square
    the terrain's tiles are drawn to."""
    positions = _edge_points(terrain)
    level = np.broadcast_to([0.0, 1.0, 0.0], positions.shape)
    return ground_colours(terrain, positions, level).mean(axis=0)


def far_ground_level(terrain: Terrain) -> float:
    """The world height (m) of the level ground past `terrain`'s square: its edge's mean."""
    return float(_edge_points(terrain)[:, 1].mean())


def far_ground_colour(terrain: Terrain, light: TerrainLight) -> np.ndarray:
    """(3,) the renderer's linear values: the level ground past `terrain`'s square, of its edge's colour, in
    `light` (the sun's beam unshadowed)."""
    up = np.array([[0.0, 1.0, 0.0]])
    return edge_colour(terrain) * (light.sun_irradiance(up) + light.unshadowed_irradiance(up))[0]


def far_ground_box(
    inverse_view_projection: np.ndarray,
    eye,
    size: tuple[int, int],
    planet_ground: tuple[float, float],
    half_side_m: float,
) -> tuple[int, int, int, int] | None:
    """The window's box (x, y from the bottom left, width, height) holding every pixel of a target of `size` seen
    through `inverse_view_projection`'s inverse from `eye` whose ray may meet the planet's ground (`planet_ground`:
    the eye's altitude over it, its radius; metres) past the terrain's square of `half_side_m` about the origin;
    None where no pixel's does.  A ray that meets that ground nearer than the square's nearest edge meets it under
    the square, where the terrain, standing above that ground, covers it; so only the box needs the ground's depth
    (`WorldPass`: a pass that writes its pixels' depth costs llvmpipe every pixel it covers, whatever is in front,
    docs/atmosphere.md#the-ground-past-the-terrain).  The rays are tested at every `BOX_STEP`-th pixel's corner and
    the box widened by a step, so that a band thinner than a step along the horizon is kept."""
    width, height = size
    x = np.unique(np.append(np.arange(0, width, BOX_STEP), width)).astype(np.float64)
    y = np.unique(np.append(np.arange(0, height, BOX_STEP), height)).astype(np.float64)
    ndc = np.stack(np.broadcast_arrays(2.0 * x[None, :] / width - 1.0, 2.0 * y[:, None] / height - 1.0), axis=-1)
    ends = [
        np.concatenate([ndc, np.full(ndc.shape[:2] + (1,), depth), np.ones(ndc.shape[:2] + (1,))], axis=-1)
        for depth in (-1.0, 1.0)
    ]
    near, far = (end @ np.asarray(inverse_view_projection, dtype=np.float64).T for end in ends)
    rays = far[..., :3] / far[..., 3:] - near[..., :3] / near[..., 3:]
    up = rays[..., 1] / np.linalg.norm(rays, axis=-1)
    altitude, radius = planet_ground
    ground = distance_to_ground(radius + altitude, up, radius)
    eye_x, eye_z = float(eye[0]), float(eye[2])
    edge = max(min(half_side_m - abs(eye_x), half_side_m - abs(eye_z)), 0.0)  # 0 off the square: any ground
    past = ground >= _EDGE_MARGIN * edge  # the sky above the horizon (inf) included
    sky = np.isinf(ground)
    # a cell between four tested corners may hold such ground unless all four see the sky or all the terrain's
    corners = np.stack([past[:-1, :-1], past[:-1, 1:], past[1:, :-1], past[1:, 1:]])
    skies = np.stack([sky[:-1, :-1], sky[:-1, 1:], sky[1:, :-1], sky[1:, 1:]])
    cells = corners.any(axis=0) & ~skies.all(axis=0)
    rows, columns = np.nonzero(cells)
    if not len(rows):
        return None
    low_x = max(x[max(columns.min() - 1, 0)], 0.0)
    high_x = min(x[min(columns.max() + 2, len(x) - 1)], width)
    low_y = max(y[max(rows.min() - 1, 0)], 0.0)
    high_y = min(y[min(rows.max() + 2, len(y) - 1)], height)
    return int(low_x), int(low_y), int(high_x - low_x), int(high_y - low_y)


def far_ground_sun(terrain: Terrain, light: TerrainLight) -> np.ndarray:
    """(3,) the part of `far_ground_colour` the sun's beam gives: what the clouds' shadows take."""
    return edge_colour(terrain) * light.sun_irradiance(np.array([[0.0, 1.0, 0.0]]))[0]


def in_shadow_map(eye, rays, space: LightSpace, half_side_m: float, level_m: float) -> np.ndarray:
    """(n,) whether each of unit `rays` (n, 3) from `eye` meets the level ground at `level_m` past the square of
    half side `half_side_m` (the terrain's) inside the footprint of the clouds' shadow map of `space`: where the
    far ground can be in a cloud's shadow.  The world pass reads the map there alone: llvmpipe runs a shader's
    branch on every pixel, and the read over the whole sky cost it a third of the world pass
    (docs/atmosphere.md#the-far-grounds-cloud-shadows)."""
    rays = np.asarray(rays, dtype=np.float64).reshape(-1, 3)
    eye = np.asarray(eye, dtype=np.float64)
    down = rays[:, 1] < 0.0
    along = np.where(down, (eye[1] - level_m) / np.where(down, -rays[:, 1], 1.0), 0.0)
    ground = eye + along[:, None] * rays
    x, y, _ = space.texel_coordinates(ground)
    width, height = space.size
    inside = (x >= 0.0) & (x <= width) & (y >= 0.0) & (y <= height)
    past = np.any(np.abs(ground[:, [0, 2]]) > half_side_m, axis=1)
    return down & (along > 0.0) & past & inside
