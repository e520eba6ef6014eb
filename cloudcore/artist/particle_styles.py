"""How each cloud's particles look besides Harris's light: sprite or splat, facing, artist shading (numpy).

A cloud is drawn as Gaussian splats in the image plane (the default), or
with `Cloud.sprite` as atlas sprites that face the eye (locked near it,
`cloudcore.artist.facing`) or lie flat (cirrus); with `Cloud.artist` it is coloured
by Wang's artist model (`cloudcore.artist.artist_shading`) instead of Harris's
scattering.  `ParticleStyles` gathers what the renderer needs for that, for
all clouds at once: per particle its cloud, shading-group centre, atlas cell
and rotation; per cloud its facing and, for artist clouds, the model's
values at the hour (`artist_uniforms`) and its vertical extent.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from cloudcore.artist.artist_shading import artist_uniforms, default_group_size, shading_groups
from cloudcore.artist.sprites import particle_sprites
from cloudcore.model.scene import Lighting
from cloudcore.world.sun import scene_hour, sun_direction

#: how a cloud's quads are oriented: splats parallel to the image plane, sprites turned toward the
#: eye (`cloudcore.artist.facing.sprite_axes`), or sprites parallel to the ground
FACING_SPLAT, FACING_CAMERA, FACING_HORIZONTAL = 0, 1, 2
_FACINGS = {"camera": FACING_CAMERA, "horizontal": FACING_HORIZONTAL}


@dataclass(frozen=True, eq=False)
class CloudStyle:
    facing: int
    #: `artist_uniforms` at the hour, with the cloud's lowest and highest particle centre; None: Harris
    artist: dict | None
    bottom_y: float
    top_y: float


@dataclass(frozen=True, eq=False)
class ParticleStyles:
    cloud_index: np.ndarray  # (n,) int64
    group_centres: np.ndarray  # (n, 3): the centre of each particle's shading group (artist clouds)
    sprite_index: np.ndarray  # (n,) int32 atlas cell, -1 for a Gaussian splat
    rotation: np.ndarray  # (n,) radians in the sprite's plane
    clouds: tuple[CloudStyle, ...]

    @functools.cached_property
    def sprite_clouds(self) -> tuple[int, ...]:
        """Clouds of eye-facing sprites: the ones whose sprites lock their facing near the eye (asked every
        frame: found once)."""
        return tuple(i for i, c in enumerate(self.clouds) if c.facing == FACING_CAMERA)

    @property
    def near_faded(self) -> np.ndarray:
        """(n,) bool: splats fade out next to the eye; sprites lock and fade by angle instead."""
        return self.sprite_index < 0


def particle_styles(clouds, lighting: Lighting) -> ParticleStyles:
    """The styles of `clouds` under `lighting` (its hour sets the artist colours and the sun they follow)."""
    hour = scene_hour(lighting)
    sun = sun_direction(hour) if not lighting.lights else np.asarray(lighting.lights[0].direction, dtype=np.float64)
    cloud_index, groups, sprites, rotations, styles = [], [], [], [], []
    for index, cloud in enumerate(clouds):
        count = len(cloud.particles)
        cloud_index.append(np.full(count, index, dtype=np.int64))
        y = cloud.centres[:, 1]
        bottom, top = (float(y.min()), float(y.max())) if count else (0.0, 0.0)
        if cloud.artist is not None and count:
            size = cloud.shading_group_size or default_group_size(cloud.radii)
            group_index, group_centres = shading_groups(cloud.centres, size)
            groups.append(group_centres[group_index])
        else:
            groups.append(cloud.centres)
        if cloud.sprite is not None:
            cells, turns = particle_sprites(cloud.sprite, cloud.centres)
        else:
            cells, turns = np.full(count, -1, dtype=np.int32), np.zeros(count)
        sprites.append(cells)
        rotations.append(turns)
        styles.append(
            CloudStyle(
                facing=FACING_SPLAT if cloud.sprite is None else _FACINGS[cloud.sprite.facing],
                artist=None if cloud.artist is None else artist_uniforms(cloud.artist, hour, sun),
                bottom_y=bottom,
                top_y=top,
            )
        )
    return ParticleStyles(
        _joined(cloud_index, np.int64, (0,)),
        _joined(groups, np.float64, (0, 3)),
        _joined(sprites, np.int32, (0,)),
        _joined(rotations, np.float64, (0,)),
        tuple(styles),
    )


def _joined(parts, dtype, empty_shape) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(empty_shape, dtype=dtype)
