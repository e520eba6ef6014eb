"""Yusov's light-space occlusion estimate: how much sunlight reaches each particle (HPG 2014, section 5.3).

Three steps, as in the paper:

1. **Tiling.** Per shadowing group (a cloud), the light's view of the particles is cut into a grid of
   `TILES` x `TILES` tiles over the group's footprint (tiles no smaller than half the median radius),
   and every particle is listed in each tile its disc (in the light's view) touches: the paper
   rasterises the particles, extended by half a tile, into per-tile linked lists; here the lists are
   one sorted array (a particle's disc bounding box is the conservative cover).
2. **Occlusion.** For each particle, the ray from its centre toward the light is intersected with
   every other particle listed in the tile its centre falls in; each one it passes through passes on
   1 - xi_j (1 - exp(-tau_j d_j)) of the light, d_j the unit-tau optical depth of the piece of the ray
   inside particle j (`cloudcore.light.precomputed` chord table: the whole chord for an occluder
   ahead, part of it where the two overlap, none behind).  The paper scales the extinction by xi to
   put back the light the strong forward lobe of the phase function scatters on (Bouthors et al.); we
   take xi_j = 1 - sigma_j / alpha_j, the share of the light a particle stops that Harris's light pass
   does not send on (`cloudcore.light.shading`): for one occluder straight ahead the estimate is then
   Harris's exact value, and a thick particle under a strongly forward phase function stops almost
   nothing, as in Harris's pass.  A particle's own extinction is not here: the precomputed scattering
   tables hold the light's path inside the particle.
3. **Smoothing.** The estimate is low-pass filtered over each particle's neighbours within its radius,
   weighted by their optical depth times the splat kernel at their distance: light diffusing through
   the body of the cloud, which the estimate alone (no light scattered between particles) leaves out.

The estimate reads no other particle's result, so it has no light order and no dependency levels:
one vectorised pass.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from cloudcore.light.precomputed import chord_depth, chord_depths
from cloudcore.maths.segments import concatenated_ranges
from cloudcore.maths.splat_kernel import splat_kernel

#: tiles across a group's footprint in the light's view (the paper's typical grid is 64 x 64)
TILES = 64


def occlusion_estimate(plane, toward_light, radii, optical_depth, xi, groups, *, smoothed: bool = True) -> np.ndarray:
    """The fraction (N,) of the light that reaches each particle centre through the other particles.

    `plane` (N, 2) are the centres in the light's view and `toward_light` (N,) their distance along the
    light (greater: nearer the light); `xi` (N,) in [0, 1] is the share of what each particle stops
    that is lost; particles only shadow particles of their own `groups` entry.
    """
    plane = np.asarray(plane, dtype=np.float64)
    n = len(plane)
    if n == 0:
        return np.zeros(0)
    target, source = _candidate_pairs(plane, radii, groups)
    # the ray from the target's centre toward the light meets the source only inside its disc, and not
    # at all where the source lies wholly behind that centre
    ahead = (toward_light[source] + radii[source] > toward_light[target]) & (target != source)
    target, source = target[ahead], source[ahead]
    gap = plane[target] - plane[source]
    squared = np.einsum("ij,ij->i", gap, gap)
    meets = squared < radii[source] ** 2
    target, source, squared = target[meets], source[meets], squared[meets]
    scale = np.maximum(radii[source], np.finfo(np.float64).tiny)
    # the ray is the light's axis through the target's centre: its distance from the source's centre is
    # the gap in the light's view, and the centre lies (toward_light difference) along it
    depth = optical_depth[source] * chord_depth(
        chord_depths(), np.sqrt(squared) / scale, (toward_light[target] - toward_light[source]) / scale
    )
    passed = 1.0 - xi[source] * -np.expm1(-depth)
    # a product over each target's occluders, as a sum of logarithms (an opaque occluder passes 0)
    logs = np.bincount(target, np.log(np.maximum(passed, np.finfo(np.float64).tiny)), minlength=n)
    occlusion = np.where(np.bincount(target, passed <= 0.0, minlength=n) > 0, 0.0, np.exp(logs))
    if smoothed:
        occlusion = _smoothed(occlusion, plane, toward_light, radii, optical_depth, groups)
    return np.clip(occlusion, 0.0, 1.0)


def _candidate_pairs(plane: np.ndarray, radii: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(target, source) for every particle and each particle listed in the tile its centre is in."""
    n = len(plane)
    tile_ids = np.zeros((n, 2), dtype=np.int64)
    first, last = np.zeros((n, 2), dtype=np.int64), np.zeros((n, 2), dtype=np.int64)
    offset = 0
    group_offset = np.zeros(n, dtype=np.int64)
    for group in np.unique(groups):
        members = np.flatnonzero(groups == group)
        low = (plane[members] - radii[members, None]).min(axis=0)
        high = (plane[members] + radii[members, None]).max(axis=0)
        # no finer than half the median radius: a disc then covers tens of tiles, not thousands
        size = max(float((high - low).max()) / TILES, 0.5 * float(np.median(radii[members])), np.finfo(np.float64).tiny)

        def tile(points, low=low, size=size):
            return np.clip(np.floor((points - low) / size).astype(np.int64), 0, TILES - 1)

        tile_ids[members] = tile(plane[members])
        first[members] = tile(plane[members] - radii[members, None])
        last[members] = tile(plane[members] + radii[members, None])
        group_offset[members] = offset
        offset += TILES * TILES
    # every (tile, particle) of the discs' covers, as one array sorted by tile: the tiles' lists
    columns = last[:, 0] - first[:, 0] + 1
    rows = last[:, 1] - first[:, 1] + 1
    cells = columns * rows
    owner = np.repeat(np.arange(n), cells)
    within = concatenated_ranges(np.zeros(n, dtype=np.int64), cells)
    u = first[owner, 0] + within % columns[owner]
    v = first[owner, 1] + within // columns[owner]
    listed_tile = group_offset[owner] + u * TILES + v
    by_tile = np.argsort(listed_tile, kind="stable")
    listed_tile, listed = listed_tile[by_tile], owner[by_tile]
    # each particle reads the list of its centre's tile
    centre_tile = group_offset + tile_ids[:, 0] * TILES + tile_ids[:, 1]
    starts = np.searchsorted(listed_tile, centre_tile, side="left")
    counts = np.searchsorted(listed_tile, centre_tile, side="right") - starts
    return np.repeat(np.arange(n), counts), listed[concatenated_ranges(starts, counts)]


def _smoothed(occlusion, plane, toward_light, radii, optical_depth, groups) -> np.ndarray:
    """Each particle's occlusion averaged over its group's particles within its radius, weighted by their
    optical depth times the splat kernel at their distance (itself at weight tau)."""
    centres = np.column_stack([plane, toward_light])
    tree = cKDTree(centres)
    neighbours = tree.query_ball_point(centres, radii, return_sorted=False)
    counts = np.array([len(found) for found in neighbours], dtype=np.int64)
    target = np.repeat(np.arange(len(centres)), counts)
    source = np.concatenate([np.asarray(found, dtype=np.int64) for found in neighbours])
    same = groups[target] == groups[source]
    target, source = target[same], source[same]
    distance = np.linalg.norm(centres[target] - centres[source], axis=1)
    weight = optical_depth[source] * splat_kernel(distance / np.maximum(radii[target], np.finfo(np.float64).tiny))
    total = np.bincount(target, weight, minlength=len(centres))
    summed = np.bincount(target, weight * occlusion[source], minlength=len(centres))
    return np.where(total > 0.0, summed / np.where(total > 0.0, total, 1.0), occlusion)
