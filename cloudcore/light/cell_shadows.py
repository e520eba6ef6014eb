"""A cloud field's clouds shadowing one another: the sun's beam to each particle through the other cells' particles,
pair by pair, made again only for the clouds a change of cells reaches.

The light-space map of `cloudcore.light.cloud_shadows` spans its clouds' footprint with a fixed count of texels and
slices: over a field's rings (a hundred kilometres across, a low sun's light crossing them tens of kilometres deep)
a texel is a kilometre and a slice many, and every cloud read as in front of every other.  Here each receiving
particle's ray toward the sun is met with the discs of the particles in front of it, as the map would with texels
and slices as fine as the particles: an occluder q of beam opacity b and radius r, whose axis passes rho from the
ray, adds -ln(1 - b K(rho / r)) times the share of its slab (2 r deep along the light) in front of the receiver
(`cloud_shadows.slab_share`).  The pairs are found in the light's plane by k-d trees, one per octave of the
occluders' radii, so the work follows the discs that overlap, not the field's extent.

Which particles shadow which: a particle casts its opacity times its blend weight (in steps) on other clouds, and
a cell takes no shadow from particles whose place lies in its own footprint (`cloudcore.field.shadow_cells`: the
rings' blend bands hold a cloud twice, their weights summing to one); the scene's own clouds are each their own
(docs/atmosphere.md, "A cloud field's clouds on one another").

A field's flight brings new cells every few frames and moves its weights' steps: `SunThroughCells` keeps each
cloud's result and, for a new set of cells or casting under the same sun, finds the clouds the particles that came,
left or changed what they cast reach (the pairs of those occluders alone) and makes only those again.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from cloudcore.field.shadow_cells import CellShadowing
from cloudcore.light.cloud_shadows import MOST_OPACITY, light_basis, slab_share
from cloudcore.maths.segments import concatenated_ranges
from cloudcore.maths.splat_kernel import splat_kernel


def _pairs(occluder_uv, occluder_radii, receiver_uv) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(occluder, receiver, distance) for every receiver point (light-plane (n, 2)) inside an occluder's disc: one
    k-d tree query per octave of the radii, so a wide particle's reach does not widen the narrow ones'."""
    found = [(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))]
    if len(occluder_radii) and len(receiver_uv):
        receivers = cKDTree(receiver_uv)
        octave = np.floor(np.log2(occluder_radii)).astype(np.int64)
        for band in np.unique(octave):  # a handful of octaves, whatever the particles' count
            members = np.flatnonzero(octave == band)
            near = cKDTree(occluder_uv[members]).sparse_distance_matrix(
                receivers, float(occluder_radii[members].max()), output_type="ndarray"
            )
            occluder = members[near["i"]]
            inside = near["v"] < occluder_radii[occluder]
            found.append((occluder[inside], near["j"][inside], near["v"][inside]))
    return tuple(np.concatenate(column) for column in zip(*found))


@dataclass
class _Particles:
    """A frame's particles seen along the sun: light-plane places, depths along the light, their clouds."""

    centres: np.ndarray  # (n, 3)
    radii: np.ndarray
    opacity: np.ndarray  # beam opacity cast on other clouds (times the particle's casting weight)
    starts: np.ndarray  # (clouds + 1,) where each cloud's particles start
    uv: np.ndarray  # (n, 2) places in the light's plane
    depth: np.ndarray  # along the light's travel
    shadowing: CellShadowing
    occluders: np.ndarray  # the particles that shadow other clouds

    def __post_init__(self):
        self.owner = np.repeat(np.arange(len(self.starts) - 1), np.diff(self.starts))

    @classmethod
    def along(cls, centres, radii, opacity, cloud_starts, shadowing: CellShadowing, sun_direction) -> _Particles:
        """The particles at `centres` (n, 3) of `radii` and beam `opacity` (cast times `shadowing`'s casting), their
        clouds at `cloud_starts`, seen along the sun's light (toward `sun_direction`)."""
        right, up, forward = light_basis(sun_direction)
        centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
        radii = np.asarray(radii, dtype=np.float64)
        opacity = np.asarray(opacity, dtype=np.float64) * shadowing.casting
        occluders = np.flatnonzero((opacity > 0.0) & (radii > 0.0))
        starts = np.asarray(cloud_starts, dtype=np.int64)
        uv = centres @ np.stack([right, up], axis=1)
        return cls(centres, radii, opacity, starts, uv, centres @ forward, shadowing, occluders)

    def of_clouds(self, clouds) -> np.ndarray:
        """The particles of `clouds` (indices), cloud after cloud."""
        clouds = np.asarray(clouds, dtype=np.int64)
        return concatenated_ranges(self.starts[clouds], self.starts[clouds + 1] - self.starts[clouds])

    def optical_depths(self, occluders, receivers) -> np.ndarray:
        """(len(receivers),) the optical depth `occluders` (particle indices) put in front of `receivers`'."""
        q, p, distance = _pairs(self.uv[occluders], self.radii[occluders], self.uv[receivers])
        q, receiver = occluders[q], receivers[p]
        # another cloud's particles in front (most pairs are a cloud's own, or behind): the cheap tests first
        keep = (self.owner[q] != self.owner[receiver]) & (self.depth[q] - self.radii[q] < self.depth[receiver])
        q, p, distance, receiver = q[keep], p[keep], distance[keep], receiver[keep]
        owner = self.owner[receiver]
        corner, side = self.shadowing.corners[owner], self.shadowing.sides[owner]
        place = self.centres[q][:, [0, 2]]
        own_cell = np.all((place >= corner) & (place < corner + side[:, None]), axis=1)  # NaN: never
        q, p, distance, receiver = q[~own_cell], p[~own_cell], distance[~own_cell], receiver[~own_cell]
        radius = self.radii[q]
        opacity = np.minimum(self.opacity[q] * splat_kernel(distance / radius), MOST_OPACITY)
        in_front = slab_share(self.depth[receiver], self.depth[q], radius)
        return np.bincount(p, weights=-np.log1p(-opacity) * in_front, minlength=len(receivers))


def sun_through_other_cells(
    centres, radii, opacity, cloud_starts, shadowing: CellShadowing, sun_direction
) -> np.ndarray:
    """(n,): the share of the sun's beam (toward `sun_direction`) the other clouds let reach each particle of the
    clouds concatenated at `cloud_starts` (`centres` (n, 3), `radii`, beam opacity `opacity`), a field's cells
    shadowing one another as `shadowing` says."""
    particles = _Particles.along(centres, radii, opacity, cloud_starts, shadowing, sun_direction)
    every = np.arange(len(particles.radii))
    return np.exp(-particles.optical_depths(particles.occluders, every))


class SunThroughCells:
    """`sun_through_other_cells` per cloud, kept between sets of clouds: for the same sun, only the clouds that
    came and those the occluders that came, left or changed reach are made again (by the clouds' identity)."""

    def __init__(self):
        self._held: tuple | None = None  # (clouds, (sun, optics), _Particles, per cloud its share)
        self.clouds_made = 0  # how many clouds the last call made (the rest were held)

    def through(
        self, clouds, centres, radii, opacity, cloud_starts, shadowing: CellShadowing, sun_direction, optics=None
    ) -> list[np.ndarray]:
        """Per cloud of `clouds` (its particles at `cloud_starts` of the concatenated arrays), the share of the
        sun's beam the other clouds let reach each particle; `optics` says what the opacities were made from (all
        is made again when it changes, as for another sun)."""
        clouds = tuple(clouds)
        sun = (tuple(float(v) for v in sun_direction), optics)
        now = _Particles.along(centres, radii, opacity, cloud_starts, shadowing, sun[0])
        held = self._held
        if held is None or held[1] != sun:
            stale = np.arange(len(clouds))
            kept: dict[int, np.ndarray] = {}
        else:
            stale, kept = self._stale(clouds, now, held)
        result = [kept.get(index) for index in range(len(clouds))]
        if len(stale):
            receivers = now.of_clouds(stale)
            made = np.exp(-now.optical_depths(now.occluders, receivers))
            for index, share in zip(stale, np.split(made, np.cumsum(np.diff(now.starts)[stale])[:-1])):
                result[index] = share
        self._held = (clouds, sun, now, result)
        self.clouds_made = len(stale)
        return result

    @staticmethod
    def _stale(clouds: tuple, now: _Particles, held: tuple) -> tuple[np.ndarray, dict[int, np.ndarray]]:
        """(the clouds to make again, the shares of the others by their index in `clouds`)."""
        before, _, then, shares = held
        place_before = {id(cloud): index for index, cloud in enumerate(before)}
        before_index = np.array([place_before.get(id(cloud), -1) for cloud in clouds], dtype=np.int64)
        came = before_index < 0
        # the occluders now whose cloud came or whose casting changed, and those before whose cloud left or whose
        # casting changed (met where and as they were)
        occluding_now, occluding_then = np.zeros(len(now.radii), bool), np.zeros(len(then.radii), bool)
        occluding_now[now.occluders], occluding_then[then.occluders] = True, True
        stayed = np.flatnonzero(~came)
        mine, theirs = now.of_clouds(stayed), then.of_clouds(before_index[stayed])
        recast = now.opacity[mine] != then.opacity[theirs]
        new_now = occluding_now.copy()
        new_now[mine] = occluding_now[mine] & (~occluding_then[theirs] | recast)
        gone_then = occluding_then.copy()
        gone_then[theirs] = occluding_then[theirs] & (~occluding_now[mine] | recast)
        changed = np.zeros(len(clouds), dtype=bool)
        changed[came] = True
        # the occluders that left (where they were) and those that came, against the particles now: one query
        gone = np.flatnonzero(gone_then)
        both = _joined(then, gone, now)
        occluders = np.concatenate([np.arange(len(gone)), len(gone) + np.flatnonzero(new_now)])
        receivers = np.arange(len(gone), len(both.radii))
        changed[now.owner[both.optical_depths(occluders, receivers) > 0.0]] = True
        kept = {int(index): shares[before_index[index]] for index in np.flatnonzero(~changed)}
        return np.flatnonzero(changed), kept


def _joined(then: _Particles, gone: np.ndarray, now: _Particles) -> _Particles:
    """The particles `gone` of `then`, each its own cloud, before those of `now` (whose clouds and footprints
    they keep), `gone` the occluders: so that the occluders that left, where they were, and those that came are
    met with the particles now in one query."""
    shadowing = CellShadowing(
        np.concatenate([np.full((len(gone), 2), np.nan), now.shadowing.corners]),
        np.concatenate([np.full(len(gone), np.nan), now.shadowing.sides]),
        np.concatenate([np.ones(len(gone)), now.shadowing.casting]),
    )
    return _Particles(
        np.concatenate([then.centres[gone], now.centres]),
        np.concatenate([then.radii[gone], now.radii]),
        np.concatenate([then.opacity[gone], now.opacity]),
        np.concatenate([np.arange(len(gone)), len(gone) + now.starts]),
        np.concatenate([then.uv[gone], now.uv]),
        np.concatenate([then.depth[gone], now.depth]),
        shadowing,
        np.arange(len(gone)),
    )
