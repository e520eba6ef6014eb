"""Yusov's precomputed lighting of the reference particle (HPG 2014, sections 4-5.1), numpy float64.

The reference particle is a unit sphere whose extinction follows the splat kernel,
beta(x) = tau K(|x|) / I_K, the same blob the path-traced truth is made of (`cloudcore.measure.truth`),
so that the optical depth through its centre is the particle's tau and a chord at distance b from the
centre has tau C(b) / C(0), C(b) the kernel's line integral.  Three tables:

* **optical depth along chords** (section 4.1): Yusov's T(phi_S, theta_S, phi_v, theta_v) is 4D because
  his particle has noise in it; ours depends on the distance to the centre only, so a ray is known by
  its distance b from the centre, and a point on it by how far along the chord it is (f: 0 entering,
  1 leaving).  `chord_depths` (b, f), for unit tau, is the optical depth from that point to where the
  ray leaves: f = 0 the whole chord, from outside.  It also gives the light's path inside a particle.
* **single scattering** (section 4.2, eq. 9, without the phase function, which is evaluated at run
  time as in the paper) and
* **multiple scattering** (section 4.3, eqs. 5-6, scattering orders 2 to `orders` iterated inside the
  sphere, each order stored at albedo 1 so that any albedo a sums them as a^n: the albedo needs no
  table dimension), as functions of the cosine mu between the view ray and the light
  (`cloudcore.light.phase` convention: +1 looking at the light) and the particle's tau.

Yusov's scattering tables are 4D (theta_S, phi_v, theta_v, rho) because each pixel looks one ray up.
A splat draws one colour per particle, its kernel spreading it: what it can show is the light leaving
the whole particle toward the eye, and the entry point drops out.  With the light's symmetry (the light
field is symmetric about the light's axis through the centre) and a distant eye, that depends on the view
only through the angle between the view ray and the light: mu.  So the tables are (tau, mu), and the
orders (tau, order, mu).  The value stored is the light leaving toward the eye per unit of the light the
particle occludes (the flux divided by the projected area weighted by opacity, integral of
1 - exp(-tau C(b)/C(0)) over the disc), for unit irradiance: times the splat's opacity alpha it is the
splat's premultiplied colour.  Thin, single scattering then tends to 1 / (4 pi), and the colour to
Harris's a tau p / (4 pi); in uniform light of radiance 1 a white particle returns alpha exactly, which
is Harris's ambient term (checked: `tests/unit/light/test_precomputed.py`).

Single scattering is a quadrature over the sphere's volume (Gauss-Legendre in radius and polar angle,
uniform in azimuth) of beta exp(-tau_light) exp(-tau_eye), both depths from the chord table.  Multiple
scattering is discrete ordinates on a voxel grid: the radiance field L(x, omega) over a product set of
directions (Gauss-Legendre in omega_z, uniform in azimuth) is transported by an upwind sweep along each
direction (the upwind point lies in the previous slice along the direction's dominant axis: bilinear
there, the source and extinction averaged over the step, exp(-dtau) exact for a constant medium), and
scattered into the next order's source by the phase matrix, whose rows are normalised over the
discrete directions so that no order gains or loses energy to the quadrature.  The light leaving
toward mu is the source of each order times the transmittance to the sphere's edge (chord table),
summed over the voxels and averaged over azimuths about the light.  Orders beyond the last are a
geometric tail, their ratio that of the last two orders.

The tables are cached on disk (`cloudcore.runtime.disk_cache`), keyed by the phase function, g, the
resolutions and `FORMAT_VERSION`; `reference_tables` builds them once (docs/shading.md has the time
and the size).
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass

import numpy as np

from cloudcore.light.phase import check_phase, phase_function
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, splat_kernel
from cloudcore.runtime import disk_cache

#: bump when what the tables hold or how they are computed changes: older cache entries are rebuilt
FORMAT_VERSION = 1
FOUR_PI = 4.0 * np.pi
#: the ratio of one scattering order to the one before, in the tail, stays below this (a white
#: particle leaks some light at every order, so the true ratio is below 1)
MAX_TAIL_RATIO = 0.999
#: orders stop once one adds less than this fraction of all before it; the geometric tail adds the rest
CONVERGED_ORDER = 1e-4


@dataclass(frozen=True)
class TableResolution:
    """The tables' resolutions: each chosen by comparing with a table twice as fine (docs/shading.md)."""

    #: chord table: distances from the centre, and positions along the chord
    chord_impacts: int = 65
    chord_positions: int = 65
    #: cosines mu between the view ray and the light at which the scattering is stored
    view_cosines: int = 33
    #: tau nodes 0 (the thin limit, exact) and 2^s for s in [log2_tau_low, log2_tau_high]: linear in tau
    #: below the first power, linear in log2 tau above; past the last the particle is opaque (its values)
    log2_tau_low: int = -3
    log2_tau_high: int = 7
    #: single scattering quadrature: radii, polar angles, azimuths
    volume_radii: int = 48
    volume_polar: int = 48
    volume_azimuths: int = 32
    #: multiple scattering: voxels across the sphere, directions (Gauss-Legendre z x azimuths),
    #: azimuths about the light averaged for the light leaving, and scattering orders computed
    voxels: int = 24
    direction_cosines: int = 12
    direction_azimuths: int = 16
    leaving_azimuths: int = 4
    orders: int = 32

    @property
    def optical_depths(self) -> np.ndarray:
        powers = 2.0 ** np.arange(self.log2_tau_low, self.log2_tau_high + 1, dtype=np.float64)
        return np.concatenate([[0.0], powers])


@dataclass(frozen=True)
class ReferenceTables:
    """The reference particle's look-up tables for one phase function (see the module docstring)."""

    #: (chord_impacts, chord_positions): unit-tau optical depth from (b, f) on a chord to where it leaves
    chord_depths: np.ndarray
    #: (taus,): the nodes
    optical_depths: np.ndarray
    #: (views,): mu, from -1 (the light behind the eye) to 1 (looking at the light)
    view_cosines: np.ndarray
    #: (taus, views): single scattering without the phase function, per unit of occluded light
    single: np.ndarray
    #: (taus, orders - 1, views): scattering orders 2, 3, ... at albedo 1, per unit of occluded light
    orders: np.ndarray
    #: (taus,): the ratio of the last order to the one before (the geometric tail's), and the last order
    tail_ratio: np.ndarray
    last_order: np.ndarray
    phase: str
    g: float
    #: seconds the build took (0 when read from the cache), and whether it was read from the cache
    build_s: float = 0.0
    cached: bool = False

    @property
    def nbytes(self) -> int:
        """Bytes the tables hold (what the cache file stores, less its key and zip headers)."""
        arrays = (self.chord_depths, self.optical_depths, self.view_cosines, self.single, self.orders)
        return int(sum(a.nbytes for a in arrays) + self.tail_ratio.nbytes + self.last_order.nbytes)

    def scattering_profiles(self, optical_depth, albedo) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per particle: (a x single scattering (n, views), multiple scattering (n, views), ambient (n,)).

        The eye pass's colour for one light is alpha (p(mu) single(mu) + multiple(mu)) E I, E the light's
        irradiance and I the fraction reaching the particle; the ambient factor is the light returned
        in uniform light of radiance 1 (per unit opacity): 2 pi times the integral over mu.
        """
        tau = np.atleast_1d(np.asarray(optical_depth, dtype=np.float64))
        albedo = np.broadcast_to(np.asarray(albedo, dtype=np.float64), tau.shape)
        low, high, weight = self._bracket(tau)
        single = albedo[:, None] * ((1.0 - weight)[:, None] * self.single[low] + weight[:, None] * self.single[high])
        multiple = (1.0 - weight)[:, None] * self._multiple(low, albedo) + weight[:, None] * self._multiple(
            high, albedo
        )
        return single, multiple, self.ambient_response(single, multiple)

    def ambient_response(self, single: np.ndarray, multiple: np.ndarray) -> np.ndarray:
        """2 pi integral over mu of (p(mu) single + multiple): the light returned in uniform light.

        The phase function is sharp where the profiles are smooth: they are interpolated onto a fine mu
        grid and the product integrated there."""
        fine = np.linspace(-1.0, 1.0, 2049)
        phase = phase_function(fine, self.phase, self.g)
        total = np.array(
            [
                np.interp(fine, self.view_cosines, s) * phase + np.interp(fine, self.view_cosines, m)
                for s, m in zip(single, multiple)
            ]
        ).reshape(len(single), len(fine))
        return 2.0 * np.pi * np.trapezoid(total, fine, axis=1)

    def _bracket(self, tau: np.ndarray):
        """The nodes below and above each tau and the weight of the upper one: linear in tau from the thin
        limit (node 0) to the first power of 2, linear in log2 tau from there."""
        first, last = self.optical_depths[1], self.optical_depths[-1]
        tau = np.clip(tau, 0.0, last)
        position = np.where(
            tau < first, tau / first, 1.0 + np.log2(np.maximum(tau, first) / first)
        )  # nodes at 0, 1, 2, ...
        low = np.clip(np.floor(position).astype(np.int64), 0, len(self.optical_depths) - 2)
        return low, low + 1, np.clip(position - low, 0.0, 1.0)

    def _multiple(self, node: np.ndarray, albedo: np.ndarray) -> np.ndarray:
        """Orders 2.. at `node` (n,) for `albedo` (n,), with the geometric tail: (n, views)."""
        count = self.orders.shape[1]
        powers = albedo[:, None] ** np.arange(2, count + 2)  # (n, orders)
        summed = np.einsum("no,nov->nv", powers, self.orders[node])
        ratio = albedo * self.tail_ratio[node]
        last = self.last_order[node]
        tail = (albedo**last * (ratio / (1.0 - ratio)))[:, None] * self.orders[node, last - 2]
        return summed + tail


@dataclass(frozen=True)
class EyePassProfiles:
    """What Yusov's eye pass needs per particle: each particle's row of `profiles`, (rows, 2, views): a x
    single scattering and multiple scattering over the uniform mu grid from -1 to 1, one row per distinct
    (tau, albedo); and the ambient response per particle (the light it returns in uniform light of
    radiance 1, per unit opacity)."""

    rows: np.ndarray
    profiles: np.ndarray
    ambient: np.ndarray

    def at(self, indices: np.ndarray, mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(a x single (n,), multiple (n,)) of particles `indices` at view-light cosines `mu` (n,), linear in
        mu between samples, as the splat shader looks them up."""
        samples = self.profiles.shape[2]
        position = (np.clip(mu, -1.0, 1.0) + 1.0) * 0.5 * (samples - 1)
        below = np.minimum(position.astype(np.int64), samples - 2)
        t = position - below
        rows = self.profiles[self.rows[indices]]  # (n, 2, views)
        low = np.take_along_axis(rows, below[:, None, None].repeat(2, 1), axis=2)[..., 0]
        high = np.take_along_axis(rows, (below + 1)[:, None, None].repeat(2, 1), axis=2)[..., 0]
        blended = (1.0 - t)[:, None] * low + t[:, None] * high
        return blended[:, 0], blended[:, 1]


def eye_pass_profiles(optical_depth, albedo, phase: str = "rayleigh", g: float = 0.0) -> EyePassProfiles:
    """Yusov's eye pass for particles of `optical_depth` and `albedo` (n,) under `phase`, `g`."""
    tau = np.asarray(optical_depth, dtype=np.float64)
    albedo = np.broadcast_to(np.asarray(albedo, dtype=np.float64), tau.shape)
    pairs, rows = np.unique(np.column_stack([tau, albedo]).reshape(-1, 2), axis=0, return_inverse=True)
    single, multiple, ambient = reference_tables(phase, g).scattering_profiles(pairs[:, 0], pairs[:, 1])
    return EyePassProfiles(rows.reshape(-1), np.stack([single, multiple], axis=1), ambient[rows.reshape(-1)])


def reference_tables(
    phase: str = "rayleigh", g: float = 0.0, resolution: TableResolution = TableResolution()
) -> ReferenceTables:
    """The tables for `phase` and `g`: from memory, from the disk cache, or built (and stored there)."""
    check_phase(phase, g)
    g = 0.0 if phase == "rayleigh" else float(g)  # Rayleigh ignores g: one table for all
    key = (phase, g, resolution)
    if key not in _held:
        _held[key] = _load_or_build(phase, g, resolution)
    return _held[key]


_held: dict[tuple, ReferenceTables] = {}


#: the disk cache's name for the tables (`cloudcore.runtime.disk_cache`)
CACHE_KIND = "reference-particle"


def cache_key(phase: str, g: float, resolution: TableResolution = TableResolution()) -> dict:
    """Every parameter the tables depend on, as the disk cache keys them."""
    return {"format": FORMAT_VERSION, "phase": phase, "g": g, "resolution": dataclasses.asdict(resolution)}


def _load_or_build(phase: str, g: float, resolution: TableResolution) -> ReferenceTables:
    start = time.perf_counter()
    arrays, cached = disk_cache.load_or_build(
        CACHE_KIND, cache_key(phase, g, resolution), lambda: build_tables(phase, g, resolution)
    )
    return ReferenceTables(
        **arrays, phase=phase, g=g, build_s=0.0 if cached else time.perf_counter() - start, cached=cached
    )


def build_tables(phase: str, g: float, resolution: TableResolution) -> dict[str, np.ndarray]:
    """The tables' arrays, computed (seconds to a minute: `reference_tables` caches them)."""
    chords = (
        chord_depths()
        if resolution == TableResolution()
        else chord_table(resolution.chord_impacts, resolution.chord_positions)
    )
    taus = resolution.optical_depths
    mu = np.linspace(-1.0, 1.0, resolution.view_cosines)
    powers = taus[1:]
    single = np.array([_single_scattering(chords, tau, mu, resolution) for tau in powers])
    occluded = np.array([_occluded_area(chords, tau) for tau in powers])
    grid = _VoxelGrid(chords, resolution, phase, g, mu)
    orders, ratios, last = zip(*(grid.multiple_scattering(tau, resolution.orders) for tau in powers))
    # the thin limit: light scattered once, unattenuated, per unit of the light occluded; no more orders
    thin_single = np.full((1, len(mu)), 1.0 / FOUR_PI)
    return {
        "chord_depths": chords,
        "optical_depths": taus,
        "view_cosines": mu,
        "single": np.concatenate([thin_single, single / occluded[:, None]]),
        "orders": np.concatenate(
            [np.zeros((1, resolution.orders - 1, len(mu))), np.array(orders) / occluded[:, None, None]]
        ),
        "tail_ratio": np.concatenate([[0.0], ratios]),
        "last_order": np.array([2, *last], dtype=np.int64),
    }


# ---------------------------------------------------------------- optical depth along chords


def chord_table(impacts: int, positions: int, nodes: int = 48) -> np.ndarray:
    """(impacts, positions): unit-tau optical depth from the point a fraction f along the chord at distance
    b from the centre to where it leaves, b and f on uniform grids over [0, 1] (Gauss-Legendre along
    each piece of chord).  Normalised by the chord through the centre, which is then exactly 1."""
    b = np.linspace(0.0, 1.0, impacts)[:, None, None]
    f = np.linspace(0.0, 1.0, positions)[None, :, None]
    half = np.sqrt(1.0 - b * b)
    start = (2.0 * f - 1.0) * half  # the point's distance along the chord from its middle
    x, w = np.polynomial.legendre.leggauss(nodes)
    u = start + (half - start) * 0.5 * (x + 1.0)  # nodes from the point to the exit
    depth = np.sum(splat_kernel(np.sqrt(b * b + u * u)) * w, axis=2) * 0.5 * (half[..., 0] - start[..., 0])
    return depth / depth[0, 0]


@functools.cache
def chord_depths() -> np.ndarray:
    """The chord table at the default resolution (milliseconds to build; the light pass's occlusion
    estimate reads it without the scattering tables)."""
    resolution = TableResolution()
    return chord_table(resolution.chord_impacts, resolution.chord_positions)


def chord_optical_depth(table: np.ndarray, points, directions) -> np.ndarray:
    """Bilinear look-up of `chord_table` for rays from `points` along unit `directions` (units of the radius)."""
    points = np.asarray(points, dtype=np.float64)
    directions = np.broadcast_to(np.asarray(directions, dtype=np.float64), points.shape)
    along = np.einsum("ij,ij->i", points, directions)
    impact = np.sqrt(np.maximum(np.einsum("ij,ij->i", points, points) - along * along, 0.0))
    return chord_depth(table, impact, along)


def chord_depth(table: np.ndarray, impact: np.ndarray, along: np.ndarray) -> np.ndarray:
    """`chord_table` at rays passing `impact` from the centre, from the point `along` the ray from its
    closest approach (negative: before it), bilinear; 0 for rays that miss."""
    half = np.sqrt(np.maximum(1.0 - impact * impact, 0.0))
    f = np.clip(np.divide(along + half, 2.0 * half, out=np.zeros_like(half), where=half > 0.0), 0.0, 1.0)
    impacts, positions = table.shape
    bi, fi = np.minimum(impact, 1.0) * (impacts - 1), f * (positions - 1)
    i = np.minimum(bi.astype(np.int64), impacts - 2)
    j = np.minimum(fi.astype(np.int64), positions - 2)
    ti, tj = bi - i, fi - j
    value = (1 - ti) * ((1 - tj) * table[i, j] + tj * table[i, j + 1]) + ti * (
        (1 - tj) * table[i + 1, j] + tj * table[i + 1, j + 1]
    )
    return np.where(impact < 1.0, value, 0.0)


def _occluded_area(chords: np.ndarray, tau: float, nodes: int = 256) -> float:
    """Integral over the unit disc of 1 - exp(-tau C(b) / C(0)): the light the particle occludes."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    b = 0.5 * (x + 1.0)
    whole = np.interp(b, np.linspace(0.0, 1.0, chords.shape[0]), chords[:, 0])
    return float(np.pi * np.sum(w * b * -np.expm1(-tau * whole)))  # 2 pi * (1/2) sum


def _light_and_leaving(mu: np.ndarray, azimuths: int) -> tuple[np.ndarray, np.ndarray]:
    """The light along +z (toward it) and unit directions (views, azimuths, 3) the light leaves in toward
    an eye whose view ray makes cosine mu with it: the leaving photons travel along -view."""
    phi = 2.0 * np.pi * (np.arange(azimuths) + 0.5) / azimuths
    sine = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))[:, None]
    leaving = np.stack(
        [sine * np.cos(phi), sine * np.sin(phi), np.broadcast_to(-mu[:, None], (len(mu), azimuths))], axis=2
    )
    return np.array([0.0, 0.0, 1.0]), leaving


def _single_scattering(chords: np.ndarray, tau: float, mu: np.ndarray, resolution: TableResolution) -> np.ndarray:
    """(views,): integral over the sphere of beta exp(-tau_light) exp(-tau_eye) / (4 pi), phase left out."""
    r, wr = np.polynomial.legendre.leggauss(resolution.volume_radii)
    c, wc = np.polynomial.legendre.leggauss(resolution.volume_polar)
    r, wr = 0.5 * (r + 1.0), 0.5 * wr
    phi = 2.0 * np.pi * (np.arange(resolution.volume_azimuths) + 0.5) / resolution.volume_azimuths
    rr, cc, pp = np.meshgrid(r, c, phi, indexing="ij")
    sine = np.sqrt(1.0 - cc * cc)
    points = np.stack([rr * sine * np.cos(pp), rr * sine * np.sin(pp), rr * cc], axis=-1).reshape(-1, 3)
    weights = (wr[:, None, None] * r[:, None, None] ** 2 * wc[None, :, None]).repeat(len(phi), 2).ravel()
    weights = weights * (2.0 * np.pi / len(phi))
    beta = tau * splat_kernel(np.linalg.norm(points, axis=1)) / KERNEL_DIAMETER_INTEGRAL
    light, leaving = _light_and_leaving(mu, 1)
    lit = beta * weights * np.exp(-tau * chord_optical_depth(chords, points, light))
    return np.array([np.sum(lit * np.exp(-tau * chord_optical_depth(chords, points, o))) for o in leaving[:, 0]]) / (
        FOUR_PI
    )


# ---------------------------------------------------------------- multiple scattering


class _VoxelGrid:
    """Discrete ordinates on a voxel grid over [-1, 1]^3 (see the module docstring)."""

    def __init__(self, chords: np.ndarray, resolution: TableResolution, phase: str, g: float, mu: np.ndarray):
        n = resolution.voxels
        self.n, self.step = n, 2.0 / n
        axis = -1.0 + self.step * (np.arange(n) + 0.5)
        self.centres = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
        self.kernel = splat_kernel(np.linalg.norm(self.centres, axis=1)) / KERNEL_DIAMETER_INTEGRAL
        self.chords = chords
        # directions: Gauss-Legendre in z times uniform azimuths; weights sum to 4 pi
        z, wz = np.polynomial.legendre.leggauss(resolution.direction_cosines)
        phi = 2.0 * np.pi * (np.arange(resolution.direction_azimuths) + 0.5) / resolution.direction_azimuths
        zz, pp = np.meshgrid(z, phi, indexing="ij")
        sine = np.sqrt(1.0 - zz * zz)
        self.directions = np.stack([sine * np.cos(pp), sine * np.sin(pp), zz], axis=-1).reshape(-1, 3)
        weights = np.repeat(wz, len(phi)) * (2.0 * np.pi / len(phi))
        light, leaving = _light_and_leaving(mu, resolution.leaving_azimuths)
        self.light = light
        self.leaving = leaving.reshape(-1, 3)
        self.views, self.leaving_azimuths = len(mu), resolution.leaving_azimuths

        def scattering_matrix(out_directions):
            # [out, in]: the share of light travelling `in` scattered into `out`; rows sum to 1
            matrix = phase_function(out_directions @ self.directions.T, phase, g) * weights
            return matrix / matrix.sum(axis=1, keepdims=True)

        self.into_directions = scattering_matrix(self.directions)
        self.into_leaving = scattering_matrix(self.leaving)
        # the sun's light travels along -light; its phase over the directions, normalised to mean 1
        from_sun = phase_function(-(self.directions @ light), phase, g)
        self.from_sun = from_sun * FOUR_PI / np.sum(from_sun * weights)
        self._sweeps = [self._sweep_group(axis, reverse) for axis in range(3) for reverse in (False, True)]
        self._sweeps = [sweep for sweep in self._sweeps if len(sweep.directions)]

    def multiple_scattering(self, tau: float, orders: int) -> tuple[np.ndarray, float, int]:
        """((orders - 1, views) light leaving per order 2..orders at albedo 1, zero past the last computed;
        the tail's ratio; the last order computed)."""
        beta = tau * self.kernel
        sun = np.exp(-tau * chord_optical_depth(self.chords, self.centres, self.light))
        to_edge = np.exp(
            -tau
            * chord_optical_depth(
                self.chords,
                np.repeat(self.centres, len(self.leaving), 0),
                np.tile(self.leaving, (len(self.centres), 1)),
            )
        ).reshape(len(self.centres), len(self.leaving))
        leaving_weight = beta[:, None] * to_edge * self.step**3
        # order 1's source: sunlight scattered once, per direction (phase over 4 pi, albedo 1)
        source = sun[:, None] * self.from_sun[None, :] / FOUR_PI  # (voxels, directions)
        passed = [np.exp(-tau * sweep.unit_depth) for sweep in self._sweeps]
        per_order = []
        for _ in range(2, orders + 1):
            radiance = self._transport(source, passed)
            source = radiance @ self.into_directions.T
            into_eye = radiance @ self.into_leaving.T  # (voxels, leaving): order n's source toward the eye
            leaving = np.sum(leaving_weight * into_eye, axis=0).reshape(self.views, self.leaving_azimuths)
            per_order.append(leaving.mean(axis=1))
            if per_order[-1].sum() < CONVERGED_ORDER * np.sum(per_order):
                break  # what is left is in the geometric tail
        last, before = per_order[-1].sum(), per_order[-2].sum() if len(per_order) > 1 else 0.0
        ratio = float(np.clip(last / before, 0.0, MAX_TAIL_RATIO)) if before > 0 else 0.0
        computed = np.zeros((orders - 1, self.views))
        computed[: len(per_order)] = per_order
        return computed, ratio, len(per_order) + 1

    def _sweep_group(self, axis: int, reverse: bool) -> _Sweep:
        """The directions swept along `axis` (their largest component), forward or reversed, with where each
        voxel's upwind point lies in the previous slice and the unit-tau depth of the step to it."""
        dominant = np.argmax(np.abs(self.directions), axis=1)
        chosen = np.flatnonzero((dominant == axis) & ((self.directions[:, axis] < 0) == reverse))
        others = [a for a in range(3) if a != axis]
        forward = np.abs(self.directions[chosen, axis])
        across = -self.directions[chosen][:, others] / forward[:, None]  # (g, 2), within [-1, 1]
        low = np.floor(across).astype(np.int64)
        n = self.n
        i = 1 + low[:, 0, None, None] + np.arange(n)[None, :, None]
        j = 1 + low[:, 1, None, None] + np.arange(n)[None, None, :]
        corners = [((i + di) * (n + 2) + (j + dj)).reshape(len(chosen), 1, n * n) for di in (0, 1) for dj in (0, 1)]
        t = across - low
        weights = [
            ((1 - t[:, 0]) * (1 - t[:, 1]))[:, None, None],
            ((1 - t[:, 0]) * t[:, 1])[:, None, None],
            (t[:, 0] * (1 - t[:, 1]))[:, None, None],
            (t[:, 0] * t[:, 1])[:, None, None],
        ]
        sweep = _Sweep(axis, reverse, chosen, corners, weights, np.zeros(0))
        kernel = sweep.oriented(np.broadcast_to(self.kernel, (len(chosen), n**3)), n)
        upwind = np.zeros_like(kernel)
        upwind[:, 1:] = sweep.upwind(kernel[:, :-1], n)
        return dataclasses.replace(sweep, unit_depth=0.5 * (kernel + upwind) * self.step / forward[:, None, None, None])

    def _transport(self, source: np.ndarray, passed) -> np.ndarray:
        """Radiance (voxels, directions) scattered by `source` upstream and carried to each voxel."""
        n = self.n
        radiance = np.empty_like(source)
        for sweep, through in zip(self._sweeps, passed):
            j = sweep.oriented(source[:, sweep.directions].T, n)  # (g, n, n, n), slice 0 upwind-most
            mean_source = j.copy()
            mean_source[:, 1:] = 0.5 * (j[:, 1:] + sweep.upwind(j[:, :-1], n))
            gained = mean_source * (1.0 - through)
            carried = np.empty_like(j)
            carried[:, 0] = gained[:, 0]
            for m in range(1, n):
                carried[:, m] = sweep.upwind(carried[:, m - 1 : m], n)[:, 0] * through[:, m] + gained[:, m]
            radiance[:, sweep.directions] = sweep.restored(carried).T
        return radiance


@dataclass(frozen=True)
class _Sweep:
    """Directions of the voxel grid swept together: the same axis and sense, each its own upwind offset."""

    axis: int
    reverse: bool
    directions: np.ndarray  # (g,) indices
    corners: list  # four (g, 1, n^2) flat indices into a zero-padded (n + 2)^2 slice
    weights: list  # their four bilinear weights, (g, 1, 1)
    unit_depth: np.ndarray  # (g, n, n, n) oriented: unit-tau optical depth of the step from upwind

    def oriented(self, fields: np.ndarray, n: int) -> np.ndarray:
        """(g, n^3) voxel fields as (g, n, n, n) with the sweep's axis first, in sweep order."""
        fields = np.moveaxis(fields.reshape(-1, n, n, n), self.axis + 1, 1)
        return fields[:, ::-1] if self.reverse else fields

    def restored(self, fields: np.ndarray) -> np.ndarray:
        """The inverse of `oriented`: (g, n^3)."""
        n = fields.shape[-1]
        fields = fields[:, ::-1] if self.reverse else fields
        return np.moveaxis(fields, 1, self.axis + 1).reshape(len(fields), n**3)

    def upwind(self, slices: np.ndarray, n: int) -> np.ndarray:
        """(g, k, n, n) slices sampled bilinearly at each direction's upwind offset, zero outside."""
        g, k = slices.shape[:2]
        padded = np.zeros((g, k, n + 2, n + 2))
        padded[:, :, 1:-1, 1:-1] = slices
        flat = padded.reshape(g, k, (n + 2) ** 2)
        total = sum(w * np.take_along_axis(flat, c, axis=2) for c, w in zip(self.corners, self.weights))
        return total.reshape(g, k, n, n)
