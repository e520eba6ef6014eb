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

from cloudcore.light.cloud_shadows import LightSpace
from cloudcore.light.terrain_light import TerrainLight
from cloudcore.scene import Terrain
from cloudcore.terrain import ground_colours, height_at
from cloudcore.terrain_tiles import tile_frame

#: points along each side of the drawn square whose ground colours are averaged into the far ground's
EDGE_SAMPLES = 64


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
