"""Harris's scaling test (GDC 2002, section 4, figure 8): 100 to 12,800 clouds of 200 particles each, the eye
moving on a circle, then straight through the clouds in its view direction.

Harris gives the counts and the two motions, not the layout; here the clouds are small cumulus
(`cloudcore.artist.cloudgen.cumulus`, 160 to 320 m across) on a jittered square grid `SPACING_M` apart
between 850 and 1,150 m up, so the field grows with the count at a constant density, as a world
filled with more sky would.  The eye flies at the clouds' height at `SPEED_M_S` (a light aircraft),
30 frames a second: on the circle (radius `CIRCLE_RADIUS_M` round the field's centre) looking along
its way, or through the field's middle along +x.  Nothing here was tuned on the level of detail:
the sizes are Harris's, the rest a plausible sky.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from cloudcore.artist.cloudgen import cumulus
from cloudcore.scene import Camera, Cloud, Scene

COUNTS = (100, 200, 400, 800, 1600, 3200, 6400, 12800)
PARTICLES_PER_CLOUD = 200
SPACING_M = 700.0
CIRCLE_RADIUS_M = 1500.0
SPEED_M_S = 60.0
FRAMES_PER_S = 30.0
CLOUD_HEIGHT_M = 1000.0


def harris_clouds(count: int, seed: int = 2002) -> tuple[Cloud, ...]:
    """`count` cumulus of `PARTICLES_PER_CLOUD` particles on a jittered grid centred on the origin."""
    rng = np.random.default_rng(seed)
    side = math.ceil(math.sqrt(count))
    clouds = []
    for index in range(count):
        row, column = divmod(index, side)
        base = np.array(
            [
                (column - (side - 1) / 2 + rng.uniform(-0.3, 0.3)) * SPACING_M,
                CLOUD_HEIGHT_M + rng.uniform(-150.0, 150.0),
                (row - (side - 1) / 2 + rng.uniform(-0.3, 0.3)) * SPACING_M,
            ]
        )
        size = np.array([rng.uniform(160, 320), rng.uniform(90, 180), rng.uniform(160, 320)])
        particles = cumulus(base, size, PARTICLES_PER_CLOUD, 0.12 * size[[0, 2]].min(), seed + index)
        clouds.append(Cloud(f"harris_{index:05d}", particles))
    return tuple(clouds)


def harris_scene(world: Scene, count: int) -> Scene:
    """`world` (its terrain, lighting and sky) with `count` of Harris's clouds and no objects."""
    return dataclasses.replace(world, clouds=harris_clouds(count), objects=(), camera=circle_views(1)[0][1])


def circle_views(frames: int) -> list:
    """(scene clock, camera) of `frames` frames on the circle round the field's centre, looking along the way."""
    step = SPEED_M_S / FRAMES_PER_S / CIRCLE_RADIUS_M  # radians a frame
    views = []
    for frame in range(frames):
        angle = frame * step
        eye = (CIRCLE_RADIUS_M * math.cos(angle), CLOUD_HEIGHT_M, CIRCLE_RADIUS_M * math.sin(angle))
        ahead = (-math.sin(angle), 0.0, math.cos(angle))
        look_at = tuple(e + 1000.0 * a for e, a in zip(eye, ahead))
        views.append((frame / FRAMES_PER_S, Camera(eye, look_at, 60.0)))
    return views


def through_views(frames: int) -> list:
    """(scene clock, camera) of `frames` frames flying along +x through the field's middle, looking ahead."""
    start = -0.5 * SPEED_M_S / FRAMES_PER_S * frames
    views = []
    for frame in range(frames):
        x = start + frame * SPEED_M_S / FRAMES_PER_S
        eye = (x, CLOUD_HEIGHT_M + 20.0, 0.5 * SPACING_M)
        views.append((frame / FRAMES_PER_S, Camera(eye, (x + 1000.0, CLOUD_HEIGHT_M + 20.0, 0.5 * SPACING_M), 60.0)))
    return views
