"""A cloud field's cells: the particles of cell (level, i, j), the same whenever it is made.

Yusov (2014, section 5.2): "Each cell contains several particle layers.  The
number of layers, as well as particle size and density, are determined by 2D
noise.  Particles in higher layers are smaller to make cumulus-like cloud
shapes with narrower tops and wider bottoms.  All particles are randomly
rotated and displaced to break repetitive patterns."

The clouds themselves belong to the plane, not to a cell or a ring: cumulus
*sites* on a jittered lattice `SITE_SPACING_CELLS` inner cells apart, each
with a strength (an integer hash, times a regional noise that gathers clouds
into clusters and leaves wide gaps of clear sky) and a reach.  The field's 2D
cloud density is the strongest site's `w (1 - rho^2)` (rho: the distance over
the site's reach, `cloud_density`); a point is cloudy where it exceeds the
threshold that makes `coverage` of the plane cloudy.  Over its footprint a
cloud is a dome on a flat base: its column's height falls from the tower's
top at the site to nothing at the rim like an ellipse, and the tower rises
by the cloud's size, its height over its footprint's radius that of the
field's cloud type (`cloudcore.artist.cloudgen.PRESETS`: humilis about as
tall as half its width, congestus three and a half times), eased into the
band of `field.altitude`, its top broken by turrets (`cumulus_columns`).  A type whose
top box is wider than the one below (the cumulonimbus) spreads an anvil there.

A cell samples that structure: `CANDIDATES_PER_SIDE`^2 jittered columns, and
in each a particle per layer of the band that the column's cloud reaches.
The lowest sits on the condensation level (the band's bottom), so every
cloud's base is flat; higher particles are smaller (Yusov), and those near a
cloud's rim smaller and sparser still: the thin wisps of its edge.  The
column spacing, and the particle radius with it, follows the cell's side, so a
coarser ring has a quarter as many particles per area, each twice as large:
the same share of the sky covered, the same clouds.  Every random choice is an
integer hash of (seed, level, layer, column) or of a site, never a
generator stream (`cloudcore.maths.noise`), so a cell is the same on every machine
and numpy.
"""

from __future__ import annotations

import functools

import numpy as np

from cloudcore.artist.cloudgen import PRESETS
from cloudcore.field.grid import cell_side
from cloudcore.maths.noise import hash01, value_noise
from cloudcore.model.scene import Cloud, CloudField

#: candidate columns along a cell's side
CANDIDATES_PER_SIDE = 8
#: a particle's radius over the column spacing in a cloud's core: neighbours overlap, no gaps between splats
RADIUS_SPACINGS = 1.7
#: how much smaller a particle at the band's top is than one on the base (Yusov's narrower tops)
TOP_SHRINK = 0.35
#: how much smaller a particle at a cloud's rim is than one in its core: the thin wisps of its edge
RIM_SHRINK = 0.25
#: the share of the columns at a cloud's rim that are kept, rising to all of them in the core: ragged, thinner edges
RIM_KEEP = 0.5
#: an anvil's particles over a core particle's radius: a sheet spread by the wind aloft, smooth where a tower's top
#: is broken into turrets
ANVIL_WIDENING = 1.6
#: the cloud sites' lattice spacing, in inner cells: clouds about a cell across (docs/scene-format.md)
SITE_SPACING_CELLS = 3.0
#: a site's reach, in site spacings (its footprint at coverage 1): reaches this long overlap everywhere
SITE_REACH = (0.8, 1.3)
#: the regional noise that gathers sites into clusters, its wavelength in site spacings
REGION_WAVELENGTH_SITES = 7.0
#: the turrets that break a tower's top: their wavelength in site spacings and how deep they cut
TURRET_WAVELENGTH_SITES = 0.3
TURRET_DEPTH = 0.3
#: what the random choices are for, mixed into their hash seeds
_JITTER_X, _JITTER_Z, _JITTER_Y, _SIZE, _RIM, _SITE_X, _SITE_Z, _SITE_REACH, _SITE_STRENGTH = range(9)
#: seeds of the regional and turret noise, apart from the hashes'
_REGION_NOISE, _TURRET_NOISE = 101, 211


def _hash(a, b, seed: int, level: int, layer: int, purpose: int) -> np.ndarray:
    """A value in [0, 1) per integer pair (a, b), one hash seed per (field seed, level, layer, purpose) within
    hash01's 64 bits."""
    return hash01(a, b, (((seed * 1_000_003 + level) * 1_009 + layer) * 16 + purpose) & (2**64 - 1))


def _sites_about(u: np.ndarray, v: np.ndarray, seed: int):
    """The 5 x 5 sites about each point (u, v), in site spacings from the field's centre: their centres' offsets
    from the point (du, dv), reaches and strengths, each (points, 25).  Every site that reaches a point is among
    them (a reach and a jitter are at most 1.3 + 0.35 spacings).  The regional noise scales the strengths where
    the point is (once a point, not once a site: a cloud thins toward a gap)."""
    offset_a, offset_b = (offset.ravel() for offset in np.meshgrid(np.arange(-2, 3), np.arange(-2, 3), indexing="ij"))
    a = (np.floor(u)[:, None] + offset_a).astype(np.int64)
    b = (np.floor(v)[:, None] + offset_b).astype(np.int64)
    site = functools.partial(_hash, a, b, seed, -1, 0)
    du = a + 0.5 + 0.7 * (site(_SITE_X) - 0.5) - u[:, None]
    dv = b + 0.5 + 0.7 * (site(_SITE_Z) - 0.5) - v[:, None]
    reach = SITE_REACH[0] + (SITE_REACH[1] - SITE_REACH[0]) * site(_SITE_REACH)
    region = 0.5 * (value_noise(u / REGION_WAVELENGTH_SITES, v / REGION_WAVELENGTH_SITES, seed + _REGION_NOISE) + 1)
    strength = site(_SITE_STRENGTH) ** 0.7 * (0.35 + 0.65 * region[:, None])
    return du, dv, reach, strength


def _site_coordinates(field: CloudField, x, z) -> tuple[np.ndarray, np.ndarray]:
    """(x, z) as flat arrays in site spacings from the field's centre."""
    spacing = SITE_SPACING_CELLS * field.cell_size
    u = (np.asarray(x, dtype=np.float64).ravel() - field.centre[0]) / spacing
    v = (np.asarray(z, dtype=np.float64).ravel() - field.centre[1]) / spacing
    return u, v


def _density(u: np.ndarray, v: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per point: each site's share `w (1 - rho^2)` (points, 25), and the sites' reaches and strengths."""
    du, dv, reach, strength = _sites_about(u, v, seed)
    return strength * (1.0 - (du * du + dv * dv) / (reach * reach)), reach, strength


def cloud_density(field: CloudField, x, z) -> np.ndarray:
    """The field's cloud density in [0, 1) at (x, z): the strongest site's share there, the same at every level."""
    shares, _, _ = _density(*_site_coordinates(field, x, z), field.seed)
    return np.maximum(shares.max(axis=1), 0.0).reshape(np.shape(x))


@functools.cache
def _density_quantiles() -> np.ndarray:
    """The density's quantiles 0, 0.001, ..., 1 over 150 x 150 site spacings (the same for every seed: the sites
    and their regional noise are stationary)."""
    u, v = np.meshgrid(np.linspace(0.0, 150.0, 300), np.linspace(0.0, 150.0, 300))
    shares, _, _ = _density(u.ravel(), v.ravel(), 0)
    return np.quantile(np.maximum(shares.max(axis=1), 0.0), np.linspace(0.0, 1.0, 1001))


def coverage_threshold(coverage: float) -> float:
    """The density above which a point is cloudy, so that `coverage` of the plane is (0: none, 1: all)."""
    if coverage <= 0.0:
        return np.inf
    if coverage >= 1.0:
        return -np.inf
    quantiles = _density_quantiles()
    return float(np.interp(1.0 - coverage, np.linspace(0.0, 1.0, len(quantiles)), quantiles))


def formation_order(field: CloudField, x, z) -> np.ndarray:
    """Per point (x, z), in [0, 1], when its cloud forms there as the field's coverage grows from none to its own:
    the coverage at which the point turns cloudy over the field's, so a cloud's core, where the density peaks, forms
    first and its rim last (and an anvil, outside every column, with the rim)."""
    quantiles = _density_quantiles()
    turns_cloudy = 1.0 - np.interp(cloud_density(field, x, z), quantiles, np.linspace(0.0, 1.0, len(quantiles)))
    if field.coverage <= 0.0:
        return np.ones(np.shape(turns_cloudy))
    return np.clip(turns_cloudy / field.coverage, 0.0, 1.0)


@functools.cache
def type_structure(cloud_type: str) -> tuple[float, float, float]:
    """(aspect, anvil_low, anvil_spread) of a cloud type, from its preset's size and boxes: a tower's height over
    its footprint's radius; and, where the preset's top box is wider than the one below it (an anvil), the share of
    the tower's height where the anvil begins and its reach over the base's (0, 0 without one)."""
    preset = PRESETS[cloud_type]
    width, height, depth = preset.size
    aspect = height / (0.25 * (width + depth))
    halves = [0.5 * ((high[0] - low[0]) + (high[2] - low[2])) for low, high in preset.boxes]
    if len(halves) > 1 and halves[-1] > halves[-2]:
        return aspect, preset.boxes[-1][0][1], halves[-1] / halves[-2]
    return aspect, 0.0, 0.0


def cumulus_columns(field: CloudField, x, z) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At each point (x, z), heights in metres above the base: the top of its cloud's column (0: clear sky), the
    bottom of the anvil above it (inf: none), the cloud's tower height, and how far the point lies toward the
    cloud's rim (0 at its site, 1 at the rim and beyond).

    A site of strength w > T (T the coverage's threshold) is cloudy out to rho_e = sqrt(1 - T / w) of its
    reach, its column there the ellipse H sqrt(1 - (rho / rho_e)^2), H = aspect * rho_e * reach eased into the
    band; turrets cut up to `TURRET_DEPTH` of it.  An anvil (`type_structure`) spreads to anvil_spread rho_e,
    from anvil_low H at the tower to the tower's top, thinning toward its rim.
    """
    threshold = coverage_threshold(field.coverage)
    u, v = _site_coordinates(field, x, z)
    shares, reach, strength = _density(u, v, field.seed)
    spacing = SITE_SPACING_CELLS * field.cell_size
    band = field.altitude[1] - field.altitude[0]
    aspect, anvil_low, anvil_spread = type_structure(field.cloud_type)
    if threshold > -np.inf:
        # (rho / rho_e)^2 = (w - share) / (w - T) for a site that is cloudy anywhere (w > T), inf otherwise
        cloudy = strength > threshold
        footprint = np.where(cloudy, 1.0 - threshold / np.where(cloudy, strength, 1.0), 0.0)
        ratio = np.where(cloudy, (strength - shares) / np.where(cloudy, strength - threshold, 1.0), np.inf)
    else:  # coverage 1: every point cloudy, every site at its full reach
        footprint, ratio = np.ones_like(shares), np.zeros_like(shares)
    # the tower the type's aspect makes, eased into the band (band (1 - e^(-H / band))): a tower taller than the
    # band is squeezed, its top still a dome, not cut flat
    towers = band * -np.expm1(-aspect * np.sqrt(footprint) * reach * spacing / band)
    heights = towers * np.sqrt(np.clip(1.0 - ratio, 0.0, 1.0))
    anvils = np.full_like(heights, np.inf)
    if anvil_spread > 0.0:
        spread = ratio / anvil_spread**2  # (rho / the anvil's reach)^2: inf where the site is clear
        under = spread < 1.0
        anvils = np.where(under, towers * (anvil_low + 0.7 * (1.0 - anvil_low) * np.where(under, spread, 0.0)), np.inf)
    # the point's column is the tallest one standing on it; above it may spread the anvil of the tallest tower whose
    # anvil reaches over it (of another cloud, or none: its own column's cloud then)
    rows = np.arange(len(u))
    owner = np.argmax(heights, axis=1)
    has_anvil = np.isfinite(anvils)
    over = np.where(has_anvil.any(axis=1), np.argmax(np.where(has_anvil, towers, -np.inf), axis=1), owner)
    height, anvil, tower = heights[rows, owner], anvils[rows, over], towers[rows, over]
    rim = np.minimum(ratio[rows, owner], 1.0)
    turrets = 0.5 * (
        value_noise(u / TURRET_WAVELENGTH_SITES, v / TURRET_WAVELENGTH_SITES, field.seed + _TURRET_NOISE) + 1.0
    )
    height = height * (1.0 - TURRET_DEPTH * turrets)
    shape = np.shape(x)
    return height.reshape(shape), anvil.reshape(shape), tower.reshape(shape), rim.reshape(shape)


def cell_cloud(field: CloudField, level: int, i: int, j: int) -> Cloud | None:
    """The cloud of cell (level, i, j), or None where the cell is clear sky (`cell_clouds` of one cell)."""
    return cell_clouds(field, [(level, i, j)])[0]


def cell_clouds(field: CloudField, cells) -> list[Cloud | None]:
    """The cloud of each cell (level, i, j) of `cells`, or None where a cell is clear sky; each cell's the same
    whether it is made alone or with others (the work is done a level and a layer at a time, for all at once).

    A cloud's particles lie inside its cell's footprint and the field's extent,
    between the altitudes of `field.altitude`, none below the bottom (the
    flat base); its optics and colour are those of `field.cloud_type`.
    """
    cells = [tuple(int(v) for v in cell) for cell in cells]
    rows: list[list[np.ndarray]] = [[] for _ in cells]
    bottom, top = field.altitude
    layer_depth = (top - bottom) / field.layers
    steps = np.arange(CANDIDATES_PER_SIDE)
    a, b = (offset.ravel() for offset in np.meshgrid(steps, steps, indexing="ij"))
    for level in sorted({cell[0] for cell in cells}):
        of_level = [index for index, cell in enumerate(cells) if cell[0] == level]
        spacing = cell_side(field, level) / CANDIDATES_PER_SIDE
        # the candidates' indices on the level's plane, cell after cell
        gx = (np.array([cells[index][1] for index in of_level])[:, None] * CANDIDATES_PER_SIDE + a).ravel()
        gz = (np.array([cells[index][2] for index in of_level])[:, None] * CANDIDATES_PER_SIDE + b).ravel()
        owner = np.repeat(of_level, len(a))
        chance = functools.partial(_hash, gx, gz, field.seed, level)
        # displaced within their spacing, never out of the cell
        x = field.centre[0] + (gx + 0.5 + 0.8 * (chance(0, _JITTER_X) - 0.5)) * spacing
        z = field.centre[1] + (gz + 0.5 + 0.8 * (chance(0, _JITTER_Z) - 0.5)) * spacing
        height, anvil, tower, rim = cumulus_columns(field, x, z)
        in_field = (np.abs(x - field.centre[0]) <= 0.5 * field.extent[0]) & (
            np.abs(z - field.centre[1]) <= 0.5 * field.extent[1]
        )
        # a rim column is kept by chance, the more likely the nearer the core: ragged edges
        in_field &= chance(0, _RIM) < 1.0 - (1.0 - RIM_KEEP) * rim**2
        core_radius = RADIUS_SPACINGS * spacing * (1.0 - RIM_SHRINK * rim**2)
        for layer in range(field.layers):
            # the bottom layer sits flat on the condensation level, half a layer deep at most; the others spread
            # through their slab
            if layer == 0:
                y = bottom + np.minimum(0.5 * core_radius, 0.5 * layer_depth)
                kept = height > 0.0
            else:
                y = bottom + (layer + 0.5 + 0.6 * (chance(layer, _JITTER_Y) - 0.5)) * layer_depth
                above = y - bottom
                in_anvil = (above > height) & (above >= anvil) & (above <= tower)
                kept = (above <= height) | in_anvil
            kept &= in_field
            if not kept.any():
                continue
            share = (y - bottom) / (top - bottom)
            radius = core_radius * (1.0 - TOP_SHRINK * share) * (0.85 + 0.3 * chance(layer, _SIZE))
            if layer > 0:
                radius = np.where(in_anvil, ANVIL_WIDENING * core_radius, radius)
            particles = np.column_stack([x, y, z, radius])[kept]
            owners = owner[kept]
            bounds = np.flatnonzero(np.diff(owners)) + 1  # the candidates are cell after cell
            for index, part in zip(owners[np.concatenate([[0], bounds])], np.split(particles, bounds)):
                rows[index].append(part)
    preset = PRESETS[field.cloud_type]
    return [
        Cloud(
            f"field_{level}_{i}_{j}",
            np.concatenate(parts),
            optical_depth=preset.optical_depth,
            albedo=preset.albedo,
            color=preset.color,
        )
        if parts
        else None
        for (level, i, j), parts in zip(cells, rows)
    ]
