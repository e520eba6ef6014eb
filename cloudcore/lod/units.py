"""What the level of detail chooses for: clouds, or groups of clouds whose particles interpenetrate.

Impostors are sorted as wholes, so where the splats of two clouds mingle in
depth, drawing one cloud's impostor over the other's is wrong wherever they
overlap on screen: bright or dark blobs that no tolerance removes (issue 16
measured them as the static error floor, 37 dB on the default view).  Harris
accepts that error; we group such clouds instead.  A group is one *unit* of
the frame plan: one bounding sphere, one representation, one impostor
rendered from all its particles in one far-to-near order, exactly as full 3D
sorts them.  Clouds that do not touch stay units of their own.

Two clouds are grouped when a splat centre of one lies within `TOUCH_RADII`
times the sum of its radius and the other cloud's largest radius of a splat
centre of the other: halfway, where each kernel exp(-4 (d/r)^2) is still
above exp(-1) of its peak.  Splats that only graze (the default scene's
bounding spheres nearly all meet) stay apart: grouping them would make
needlessly large impostors for an error below 8-bit precision.

A group costs motion: its sphere is larger than its clouds', so a moving eye
remakes its impostor sooner, and every particle of it each time.  While the
eye moves, auto mode plans a group apart (`LodUnits.apart_rows`), its clouds each
a unit of its own, where their impostors cost less than the group's
(`cloudcore.lod.plan`, docs/lod.md); with the eye still, or inside its
sphere, the group is whole.  Pure numpy and scipy.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from cloudcore.lod.costs import SPRITE_FRAGMENT_COST
from cloudcore.model.scene import splats_bounding_sphere

#: two splats interpenetrate when their centres are closer than this times the sum of their radii
TOUCH_RADII = 0.5
#: splats per cloud (`SplatSample`) that count a far unit the frustum cuts: the share of them in view, a
#: binomial estimate, is within 6% (one standard deviation) of the count of every splat, and a frame's sum over
#: its cut units far closer: over the 1.2M-particle field's 30 bench frames 0.5% at most, over the cumulus
#: field's 989 frames 0.3% on average and 4.4% at most (256 splats: 0.1% and 1.2%, at twice the time)
SAMPLE_PER_CLOUD = 64


def concatenated_ranges(firsts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The integers firsts[i] .. firsts[i] + counts[i] - 1, for each i in turn, without a Python loop."""
    firsts, counts = np.asarray(firsts, dtype=np.int64), np.asarray(counts, dtype=np.int64)
    offsets = np.cumsum(counts) - counts
    return np.arange(int(np.sum(counts)), dtype=np.int64) + np.repeat(firsts - offsets, counts)


@dataclass(frozen=True, eq=False)
class SplatSample:
    """Every k-th splat of each cloud, about `SAMPLE_PER_CLOUD` of them, each standing for k: what the plan
    counts the splats in view of a far unit the frustum cuts by, copied once when the units are made (the
    1.2M-particle field's: 29,000 splats, 1.2 MB, 1.4 ms) so that a frame gathers them without a loop over clouds."""

    centres: np.ndarray  # (samples, 3)
    radii: np.ndarray  # (samples,)
    weights: np.ndarray  # (samples,) the cloud's splats each stands for
    cloud_starts: np.ndarray  # (clouds + 1,) cloud c's samples are cloud_starts[c]:cloud_starts[c + 1]

    @staticmethod
    def of(centres: np.ndarray, radii: np.ndarray, cloud_starts: np.ndarray) -> SplatSample:
        """The sample of splats (`centres`, `radii`) whose cloud c is cloud_starts[c]:cloud_starts[c + 1]."""
        starts = np.asarray(cloud_starts, dtype=np.int64)
        counts = np.diff(starts)
        strides = np.maximum(1, counts // SAMPLE_PER_CLOUD)
        taken = -(-counts // strides)  # ceil: the strided slice's length
        steps = concatenated_ranges(np.zeros(len(counts)), taken)
        rows = np.repeat(starts[:-1], taken) + np.repeat(strides, taken) * steps
        return SplatSample(
            np.asarray(centres, dtype=np.float64)[rows].reshape(-1, 3),
            np.asarray(radii, dtype=np.float64)[rows],
            np.repeat(counts / np.maximum(taken, 1), taken),
            np.concatenate([[0], np.cumsum(taken)]),
        )

    def of_clouds(self, clouds, owners) -> tuple:
        """(owners, centres, radii, weights) of the samples of `clouds`, each sample's owner that of its cloud."""
        clouds = np.asarray(clouds, dtype=np.int64)
        firsts = self.cloud_starts[clouds]
        counts = self.cloud_starts[clouds + 1] - firsts
        rows = concatenated_ranges(firsts, counts)
        return np.repeat(owners, counts), self.centres[rows], self.radii[rows], self.weights[rows]


@dataclass(frozen=True, eq=False)
class LodUnits:
    """The frame plan's units: bounding spheres, member clouds, and what the cost model needs of each."""

    centres: np.ndarray  # (units, 3) bounding-sphere centres
    radii: np.ndarray  # (units,) bounding radii (0: no particles)
    members: tuple  # per unit, its clouds' indices, ascending
    particle_counts: np.ndarray  # (units,) particles
    radius_squares: np.ndarray  # (units,) sum of the particles' squared radii, m^2: their splats' area
    finest_radii: np.ndarray  # (units,) metres: the finest detail in the unit (0: unknown)
    #: (units,) what a fragment of the unit's splats costs, in fragments of Gaussian kernel splats (area-weighted:
    #: an atlas sprite's is `cloudcore.lod.costs.SPRITE_FRAGMENT_COST`)
    fragment_costs: np.ndarray
    #: a unit of its own for each cloud of a group, for a group planned apart (`apart_rows`; None: no groups)
    clouds: LodUnits | None = None
    sample: SplatSample | None = None  # of every cloud's splats (None: only the spheres are known)
    #: (units, 2) metres: the lowest and the highest reach of the unit's splats (None: only the spheres are known).
    #: A cloud field's cells are flat (a coarse cell kilometres wide, its clouds a band of hundreds of metres), and
    #: their spheres reach far above and below what they hold (Wang's ring's elevation band: `ring_members`)
    heights: np.ndarray | None = None
    #: (units,) how many times finer than `RenderSettings.impostor_detail_texels` asks the unit's impostor is made
    #: where its detail bounds it (`FIELD_CELL_DETAIL_SCALE` for a cloud field's cells; None: 1 for every unit)
    detail_scales: np.ndarray | None = None

    @functools.cached_property
    def and_clouds(self) -> LodUnits:
        """These units, then `clouds`: what a frame with groups planned apart takes its units from (`apart_rows`),
        priced in one pass."""
        if self.clouds is None:
            return self
        parts = (self, self.clouds)
        return LodUnits(
            np.concatenate([u.centres for u in parts]),
            np.concatenate([u.radii for u in parts]),
            self.members + self.clouds.members,
            np.concatenate([u.particle_counts for u in parts]),
            np.concatenate([u.radius_squares for u in parts]),
            np.concatenate([u.finest_radii for u in parts]),
            np.concatenate([u.fragment_costs for u in parts]),
            sample=self.sample,
            heights=None if self.heights is None else np.concatenate([u.heights for u in parts]),
            detail_scales=None if self.detail_scales is None else np.concatenate([u.texel_scales for u in parts]),
        )

    @property
    def texel_scales(self) -> np.ndarray:
        """(units,) `detail_scales`, 1 where none are given."""
        return np.ones(len(self.radii)) if self.detail_scales is None else self.detail_scales

    @functools.cached_property
    def member_counts(self) -> np.ndarray:
        """Clouds per unit."""
        return np.fromiter(map(len, self.members), dtype=np.int64, count=len(self.members))

    @functools.cached_property
    def member_set(self) -> frozenset:
        """The units' members, as a set."""
        return frozenset(self.members)

    @functools.cached_property
    def row_of(self) -> dict:
        """Each unit's row, by its members."""
        return {members: row for row, members in enumerate(self.members)}

    @functools.cached_property
    def group_rows(self) -> np.ndarray:
        """The rows of the units of more than one cloud."""
        return np.array([row for row, members in enumerate(self.members) if len(members) > 1], dtype=np.int64)

    @functools.cached_property
    def groups(self) -> LodUnits:
        """The units of more than one cloud (`group_rows`), on their own: auto mode prices them every frame its
        eye moves (`cloudcore.lod.plan.choice.groups_cheaper_apart`)."""
        return self.take(self.group_rows)

    def apart_rows(self, groups: frozenset) -> np.ndarray:
        """The rows of `and_clouds` of these units with each group of `groups` (their members) replaced, in
        place, by its clouds' own units."""
        row_of = {members[0]: len(self.members) + row for row, members in enumerate(self.clouds.members)}
        return np.array(
            [
                row_of[cloud] if members in groups else index
                for index, members in enumerate(self.members)
                for cloud in (members if members in groups else members[:1])
            ],
            dtype=np.int64,
        )

    def take(self, rows) -> LodUnits:
        """The units at `rows` (an array of indices), on their own (without `clouds`)."""
        return LodUnits(
            self.centres[rows],
            self.radii[rows],
            tuple(self.members[row] for row in rows),
            self.particle_counts[rows],
            self.radius_squares[rows],
            self.finest_radii[rows],
            self.fragment_costs[rows],
            sample=self.sample,
            heights=None if self.heights is None else self.heights[rows],
            detail_scales=None if self.detail_scales is None else self.detail_scales[rows],
        )

    def member_means(self, per_cloud: np.ndarray) -> np.ndarray:
        """(units, 3): the mean over each unit's clouds of `per_cloud` (clouds, 3), without a loop over units."""
        per_cloud = np.asarray(per_cloud, dtype=np.float64).reshape(-1, 3)
        if not self.members:
            return np.zeros((0, 3))
        flat = np.fromiter(itertools.chain.from_iterable(self.members), dtype=np.int64)
        return np.add.reduceat(per_cloud[flat], self._member_firsts, axis=0) / self.member_counts[:, None]

    @functools.cached_property
    def _member_firsts(self) -> np.ndarray:
        return np.concatenate([[0], np.cumsum(self.member_counts)[:-1]]).astype(np.int64)

    def moved(self, cloud_shifts: np.ndarray, grown: float) -> LodUnits:
        """These units with their clouds moved by `cloud_shifts` (clouds, 3) metres and each cloud's particles
        strayed at most `grown` metres besides (the wind: `cloudcore.world.wind`): a unit moves by its members' mean
        shift, and its sphere grows by `grown` and by the farthest a member moved from that mean."""
        cloud_shifts = np.asarray(cloud_shifts, dtype=np.float64).reshape(-1, 3)
        shifts, spread = self.member_means(cloud_shifts), np.zeros(len(self.members))
        if self.members:
            flat = np.fromiter(itertools.chain.from_iterable(self.members), dtype=np.int64)
            apart = np.linalg.norm(cloud_shifts[flat] - np.repeat(shifts, self.member_counts, axis=0), axis=1)
            spread = np.maximum.reduceat(apart, self._member_firsts)
        sample = self.sample
        if sample is not None:
            per_sample = np.repeat(cloud_shifts, np.diff(sample.cloud_starts), axis=0)
            sample = dataclasses.replace(sample, centres=sample.centres + per_sample)
        reach = grown + spread
        return dataclasses.replace(
            self,
            centres=self.centres + shifts,
            radii=np.where(self.radii > 0.0, self.radii + reach, 0.0),
            heights=None if self.heights is None else self.heights + shifts[:, 1:2] + np.column_stack([-reach, reach]),
            clouds=None if self.clouds is None else self.clouds.moved(cloud_shifts, grown),
            sample=sample,
        )

    @staticmethod
    def of_spheres(centres, radii, finest_radii=None, particle_counts=None, radius_squares=None) -> LodUnits:
        """One unit per sphere (tests, and scenes planned without particles)."""
        radii = np.asarray(radii, dtype=np.float64).reshape(-1)
        count = len(radii)
        zeros = np.zeros(count)
        return LodUnits(
            np.asarray(centres, dtype=np.float64).reshape(-1, 3),
            radii,
            tuple((i,) for i in range(count)),
            zeros if particle_counts is None else np.asarray(particle_counts, dtype=np.float64),
            zeros if radius_squares is None else np.asarray(radius_squares, dtype=np.float64),
            zeros if finest_radii is None else np.asarray(finest_radii, dtype=np.float64),
            np.ones(count),
        )


def interpenetrating_groups(
    centres: np.ndarray,
    radii: np.ndarray,
    cloud_starts: np.ndarray,
    sphere_centres: np.ndarray,
    sphere_radii: np.ndarray,
) -> tuple:
    """Clouds grouped by interpenetrating splats (connected components), each group's clouds ascending, groups
    ordered by their first cloud.  Only pairs whose bounding spheres meet are looked at."""
    clouds = len(sphere_radii)
    # the pairs of spheres that meet, from a tree of their centres: all pairs at once would take clouds^2 memory
    # (3.9 GB for Harris's 12,800 clouds)
    reach = 2.0 * float(np.max(sphere_radii, initial=0.0))
    pairs = cKDTree(sphere_centres).query_pairs(reach, output_type="ndarray") if clouds else np.zeros((0, 2), int)
    first, second = pairs[:, 0], pairs[:, 1]
    gaps = np.linalg.norm(sphere_centres[first] - sphere_centres[second], axis=1)
    meet = (gaps < sphere_radii[first] + sphere_radii[second]) & (sphere_radii[first] > 0) & (sphere_radii[second] > 0)
    candidates = pairs[meet]
    trees: dict[int, cKDTree] = {}

    def tree(cloud: int) -> cKDTree:
        if cloud not in trees:
            trees[cloud] = cKDTree(centres[cloud_starts[cloud] : cloud_starts[cloud + 1]])
        return trees[cloud]

    touching = []
    for a, b in candidates:
        a_radii = radii[cloud_starts[a] : cloud_starts[a + 1]]
        b_largest = radii[cloud_starts[b] : cloud_starts[b + 1]].max()
        nearest, _ = tree(b).query(
            centres[cloud_starts[a] : cloud_starts[a + 1]],
            k=1,
            distance_upper_bound=TOUCH_RADII * (a_radii.max() + b_largest),
        )
        if np.any(nearest < TOUCH_RADII * (a_radii + b_largest)):
            touching.append((a, b))
    pairs = np.array(touching, dtype=np.int64).reshape(-1, 2)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(clouds, clouds))
    _, labels = connected_components(graph, directed=False)
    groups: dict[int, list[int]] = {}
    for cloud, label in enumerate(labels):
        groups.setdefault(int(label), []).append(cloud)
    return tuple(sorted((tuple(g) for g in groups.values()), key=lambda g: g[0]))


#: a cloud field's cell's impostor is made this many times finer than `impostor_detail_texels` asks where its detail
#: bounds it: a cell's remake splats a few dozen particles, so its texels cost little, while its near cells' splats,
#: a hundred metres wide, are magnified many times on the screen and smoothed by the coarser texture's bilinear
#: read (measured on the cumulus field's flight: docs/performance.md, "The field's impostors within 35 dB")
FIELD_CELL_DETAIL_SCALE = 2.0


def lod_units(particles, group: bool = True, groupable: int | None = None) -> LodUnits:
    """The units of a `ParticleBuffer`: its clouds, interpenetrating ones grouped (`group`).

    Only the first `groupable` clouds (None: all) are grouped; the others are units of their own: a cloud
    field's cells, whose nested grid is their level of detail (grouping the touching cells of a field would
    make it one unit to the horizon, beyond any impostor or ring), their impostors made finer
    (`FIELD_CELL_DETAIL_SCALE`).
    """
    starts = particles.cloud_starts
    sphere_centres, sphere_radii = particles.bounding_centres, particles.bounding_radii
    clouds = len(sphere_radii)
    grouped = clouds if groupable is None else min(groupable, clouds)
    members = (
        interpenetrating_groups(
            particles.centres, particles.radii, starts[: grouped + 1], sphere_centres[:grouped], sphere_radii[:grouped]
        )
        if group and grouped
        else tuple((i,) for i in range(grouped))
    ) + tuple((i,) for i in range(grouped, clouds))
    sample = SplatSample.of(particles.centres, particles.radii, starts)
    cells = clouds - grouped
    scales = np.concatenate([np.ones(len(members) - cells), np.full(cells, FIELD_CELL_DETAIL_SCALE)]) if cells else None
    units = dataclasses.replace(_units_of(particles, members), sample=sample, detail_scales=scales)
    in_groups = tuple((cloud,) for unit in members if len(unit) > 1 for cloud in unit)
    if not in_groups:
        return units
    return dataclasses.replace(units, clouds=dataclasses.replace(_units_of(particles, in_groups), sample=sample))


def _units_of(particles, members: tuple) -> LodUnits:
    """The units of `particles` whose clouds are `members` (one tuple of cloud indices per unit)."""
    starts = particles.cloud_starts
    sphere_centres, sphere_radii = particles.bounding_centres, particles.bounding_radii
    centres, radii, counts, squares, finest, fragment_costs, heights = [], [], [], [], [], [], []
    fill_costs = np.where(particles.styles.sprite_index >= 0, SPRITE_FRAGMENT_COST, 1.0)
    for clouds in members:
        ranges = [np.arange(starts[c], starts[c + 1]) for c in clouds]
        indices = np.concatenate(ranges)
        if len(clouds) == 1:
            centre, radius = sphere_centres[clouds[0]], sphere_radii[clouds[0]]
        else:
            centre, radius = splats_bounding_sphere(particles.centres[indices], particles.radii[indices])
        centres.append(centre)
        radii.append(radius)
        counts.append(len(indices))
        areas = particles.radii[indices] ** 2
        squares.append(float(np.sum(areas)))
        fragment_costs.append(float(np.dot(areas, fill_costs[indices]) / squares[-1]) if squares[-1] > 0.0 else 1.0)
        detail = [particles.finest_radii[c] for c in clouds if particles.finest_radii[c] > 0.0]
        finest.append(min(detail) if detail else 0.0)
        splat_y, splat_radii = particles.centres[indices, 1], particles.radii[indices]
        heights.append((np.min(splat_y - splat_radii), np.max(splat_y + splat_radii)) if len(indices) else (0.0, 0.0))
    return LodUnits(
        np.array(centres, dtype=np.float64).reshape(-1, 3),
        np.array(radii, dtype=np.float64),
        members,
        np.array(counts, dtype=np.float64),
        np.array(squares, dtype=np.float64),
        np.array(finest, dtype=np.float64),
        np.array(fragment_costs, dtype=np.float64),
        heights=np.array(heights, dtype=np.float64).reshape(-1, 2),
    )
