"""Which way atlas sprites face: the in-cloud facing lock (Wang 2004, section 3.3) and the sprites' corners.

A sprite turned toward the eye swings wildly when the eye is next to its
centre, and sprites "move out of the way of the oncoming camera": Wang's
"parting of the Red Sea".  His cure: lock a sprite's facing when the camera
comes within half of the sprite's radius, and, since the camera may then
pivot until it sees the locked sprite edge-on, fade the sprite by the angle
between its locked facing and the vector to the camera.

`FacingLocks` keeps that state for one particle set from frame to frame;
`sprite_corners` is the reference for the vertex shader that builds the quads.
All sprites (locked or not) use the same in-plane axes (`sprite_axes`: up is
world up projected into the sprite's plane), so nothing turns in its plane at
the moment a sprite locks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.maths.ramps import smoothstep
from cloudcore.maths.vectors import row_lengths, unit_rows

#: Wang: lock "when the camera comes within half of the sprite radius"
LOCK_RADII = 0.5
#: unlock only beyond 10% more.  A camera hovering on the lock sphere (or a path's rounding) would
#: otherwise lock and unlock on alternate frames, and each new lock takes a new facing: the sprite
#: would jump.  Ten percent is far wider than any rounding, and narrow enough that a sprite the camera
#: has left turns back to face it almost at once.
UNLOCK_RADII = 1.1 * LOCK_RADII
#: the facing of a sprite whose centre the eye sits on before it was ever anywhere else
FALLBACK_NORMAL = (0.0, 0.0, 1.0)
WORLD_UP = np.array([0.0, 1.0, 0.0])
#: where the sprite faces straight up or down (its normal's horizontal part below VERTICAL_TOLERANCE),
#: its up is north instead (world -z)
NORTH = np.array([0.0, 0.0, -1.0])
VERTICAL_TOLERANCE = 1e-6
#: the normal of a "horizontal" sprite (Wang's cirrus quads, parallel to the ground)
HORIZONTAL_NORMAL = (0.0, 1.0, 0.0)
#: quad corners in (right, up) half-sizes, counter-clockwise as seen from the side the normal points to;
#: texture coordinates (u0, v1), (u1, v1), (u1, v0), (u0, v0) of `cloudcore.artist.sprites.atlas_cell_uv`
CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
_FAR = 1e150


@dataclass(frozen=True, eq=False)
class FacingState:
    """One frame of the facing lock for n particles.

    locked (n,) bool: within the lock radius (with hysteresis).
    normals (n, 3) unit: the direction each sprite faces, from its centre toward
        the eye: for a locked sprite the direction at the moment it locked,
        for the others the current one.
    fade (n,) in [0, 1]: multiplies a sprite's opacity; 1 unless locked.
    """

    locked: np.ndarray
    normals: np.ndarray
    fade: np.ndarray


def lock_fade(cos_angle) -> np.ndarray:
    """A locked sprite's opacity factor from the cosine of the angle between its facing and the eye.

    smoothstep(0, 1, cos): 1 facing the eye, 0 from 90 degrees on.  A sprite's
    projected area shrinks as the cosine; at 90 degrees it is edge-on (a sliver
    that would flicker) and beyond it is seen from behind, where a facing
    sprite is never seen, so it must be gone by then.  The smoothstep, flat at
    both ends, keeps small head turns inside a cloud from dimming the sprites
    and lets them vanish without a kink.
    """
    return smoothstep(0.0, 1.0, cos_angle)


class FacingLocks:
    """The facing lock of one set of `count` camera-facing sprites, updated once per frame (Wang section 3.3)."""

    def __init__(self, count: int):
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
            raise ValueError(f"count must be an integer >= 0, got {count!r}")
        self._locked = np.zeros(count, dtype=bool)
        self._normals = np.tile(FALLBACK_NORMAL, (count, 1))
        # the last defined particle->eye direction: what an eye exactly at a centre is taken to see
        self._directions = self._normals.copy()

    @property
    def any_locked(self) -> bool:
        """Whether a sprite is locked now.  With none locked and the eye outside the cloud's bounding
        sphere nothing can lock this frame, so a renderer may skip `update` for far clouds."""
        return bool(self._locked.any())

    def update(self, eye, centres, radii) -> FacingState:
        """Lock the sprites the eye has come within LOCK_RADII radii of, unlock those it has left
        (beyond UNLOCK_RADII), and return this frame's state.

        Vectorised over all particles (about 4 ms for 90,000); the arrays
        returned are read-only.  An eye exactly at a sprite's centre has no
        direction to it: the last one is kept (FALLBACK_NORMAL before any).
        """
        eye = np.asarray(eye, dtype=np.float64)
        centres = np.asarray(centres, dtype=np.float64)
        radii = np.asarray(radii, dtype=np.float64)
        count = len(self._locked)
        if eye.shape != (3,) or centres.shape != (count, 3) or radii.shape != (count,):
            raise ValueError(
                f"expected an eye (3,), centres ({count}, 3) and radii ({count},), "
                f"got {eye.shape}, {centres.shape} and {radii.shape}"
            )
        if not (np.all(np.isfinite(eye)) and np.all(np.isfinite(centres)) and np.all(np.isfinite(radii))):
            raise ValueError("eye, centres and radii must be finite")
        with np.errstate(over="ignore"):
            # a sprite this far is never locked; clipping keeps the squares below finite
            offsets = np.clip(eye - centres, -_FAR, _FAR)
        distances = row_lengths(offsets)
        at_centre = distances == 0.0
        directions = offsets / np.where(at_centre, 1.0, distances)[:, None]
        directions[at_centre] = self._directions[at_centre]
        locked = np.where(self._locked, distances <= UNLOCK_RADII * radii, distances < LOCK_RADII * radii)
        normals = directions.copy()
        kept = np.flatnonzero(locked & self._locked)
        normals[kept] = self._normals[kept]
        fade = np.ones(count)
        in_lock = np.flatnonzero(locked)
        fade[in_lock] = lock_fade(np.einsum("ij,ij->i", normals[in_lock], directions[in_lock]))
        for array in (locked, normals, directions, fade):
            array.flags.writeable = False  # shared between the state returned and the next update
        self._locked, self._normals, self._directions = locked, normals, directions
        return FacingState(locked, normals, fade)


def sprite_axes(normals) -> tuple[np.ndarray, np.ndarray]:
    """Each sprite's in-plane (right, up) unit axes (n, 3) for unit `normals` (n, 3) pointing to the viewer.

    up is world up projected into the sprite's plane, right = up x normal
    (screen right for a viewer looking along -normal); a sprite facing
    straight up or down takes north (world -z) as its up reference instead.
    """
    normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    # the test is on the horizontal part, which float32 (the shader's) still resolves at 1e-6
    vertical = np.hypot(normals[:, 0], normals[:, 2]) < VERTICAL_TOLERANCE
    reference = np.where(vertical[:, None], NORTH, WORLD_UP)
    rights = unit_rows(np.cross(reference, normals))
    ups = np.cross(normals, rights)
    return rights, ups


def sprite_corners(centres, radii, normals, rotations) -> np.ndarray:
    """World corners (n, 4, 3) of each sprite's quad, in `CORNERS` order.

    A quad of side 2 radius in the plane through the centre perpendicular to
    its normal, turned by `rotations` (radians, counter-clockwise as seen
    from the side its normal points to) about the normal.  The vertex shader
    builds the same corners from the same inputs.
    """
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    rotations = np.asarray(rotations, dtype=np.float64).reshape(-1)
    rights, ups = sprite_axes(normals)
    cos, sin = np.cos(rotations)[:, None], np.sin(rotations)[:, None]
    x, y = CORNERS[:, 0], CORNERS[:, 1]  # (4,)
    along_right = radii[:, None] * (cos * x - sin * y)  # (n, 4)
    along_up = radii[:, None] * (sin * x + cos * y)
    return centres[:, None, :] + along_right[..., None] * rights[:, None, :] + along_up[..., None] * ups[:, None, :]


class CloudFacings:
    """The facing locks of every cloud of eye-facing sprites in a particle set, frame to frame.

    `particles` is a `cloudcore.particles.buffer.ParticleBuffer`.  Only clouds
    whose bounding sphere holds the eye, or that still have a sprite locked,
    are looked at: elsewhere no sprite is within its lock radius.
    """

    def __init__(self, particles):
        self._particles = particles
        self._locks: dict[int, FacingLocks] = {}

    def update(self, eye, particles=None) -> list[tuple[int, FacingState]]:
        """(first particle, state) of each cloud whose locks were updated for `eye` this frame; `particles`: where
        the frame has the particles, when the wind has carried them on (`ParticleBuffer.carried`, the same clouds)."""
        particles = self._particles if particles is None else particles
        eye = np.asarray(eye, dtype=np.float64)
        updated = []
        for cloud in particles.styles.sprite_clouds:
            locks = self._locks.get(cloud)
            inside = np.linalg.norm(eye - particles.bounding_centres[cloud]) <= particles.bounding_radii[cloud]
            if not inside and (locks is None or not locks.any_locked):
                continue
            start, stop = particles.cloud_starts[cloud], particles.cloud_starts[cloud + 1]
            if locks is None:
                locks = self._locks[cloud] = FacingLocks(int(stop - start))
            updated.append((int(start), locks.update(eye, particles.centres[start:stop], particles.radii[start:stop])))
        return updated
