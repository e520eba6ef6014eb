"""A cloud field's cells: the particles of cell (level, i, j), the same whenever it is made.

Yusov (2014, section 5.2): "Each cell contains several particle layers.  The
number of layers, as well as particle size and density, are determined by 2D
noise.  Particles in higher layers are smaller to make cumulus-like cloud
shapes with narrower tops and wider bottoms.  All particles are randomly
rotated and displaced to break repetitive patterns."

Here a cell holds `CANDIDATES_PER_SIDE`^2 candidate particles a layer on a
jittered grid; a candidate is kept where the field's cloud density (2D value
noise, `cloud_density`) exceeds the threshold that makes `coverage` of the
plane cloudy, and in higher layers only where it exceeds it by more.  The
candidate spacing, and with it the particle radius, follows the cell's side,
so a coarser ring has a quarter as many particles per area, each twice as
large: the same share of the sky covered.  Every random choice is an integer
hash of (seed, level, layer, candidate), never a generator stream
(`cloudcore.noise`), so a cell is the same on every machine and numpy.
"""

from __future__ import annotations

import functools

import numpy as np

from cloudcore.artist.cloudgen import PRESETS
from cloudcore.field.grid import cell_side
from cloudcore.noise import hash01, value_noise
from cloudcore.scene import Cloud, CloudField

#: candidate particles along a cell's side, per layer
CANDIDATES_PER_SIDE = 6
#: the cloud density's largest wavelength, in inner cells: clouds about an inner cell across
NOISE_WAVELENGTH_CELLS = 2.0
#: a particle's radius over the candidate spacing: neighbours overlap, no gaps between splats
RADIUS_SPACINGS = 1.1
#: how much smaller a particle of the top layer is than one of the bottom layer
TOP_SHRINK = 0.35
#: the share of the density above the threshold that the top layer needs: narrower tops
TOP_HEADROOM = 0.7
#: octaves of the cloud density: (frequency, amplitude)
_OCTAVES = ((1.0, 0.6), (2.03, 0.3), (4.11, 0.1))
#: what the random choices are for, mixed into their hash seeds
_JITTER_X, _JITTER_Z, _JITTER_Y, _SIZE = range(4)


def cloud_density(field: CloudField, x, z) -> np.ndarray:
    """The field's cloud density in [0, 1] at (x, z): fractal value noise, the same at every level."""
    wavelength = NOISE_WAVELENGTH_CELLS * field.cell_size
    u = (np.asarray(x, dtype=np.float64) - field.centre[0]) / wavelength
    v = (np.asarray(z, dtype=np.float64) - field.centre[1]) / wavelength
    return _fractal_noise(u, v, field.seed)


def _fractal_noise(u: np.ndarray, v: np.ndarray, seed: int) -> np.ndarray:
    """Octaves of value noise at (u, v), in wavelengths of the first, mapped to [0, 1]."""
    total = sum(
        amplitude * value_noise(frequency * u, frequency * v, seed + octave)
        for octave, (frequency, amplitude) in enumerate(_OCTAVES)
    )
    return 0.5 * (total + 1.0)


@functools.cache
def _density_quantiles() -> np.ndarray:
    """The density's quantiles 0, 0.001, ..., 1 over 200 x 200 wavelengths (the same for every seed: value noise
    is stationary)."""
    u, v = np.meshgrid(np.linspace(0.0, 200.0, 400), np.linspace(0.0, 200.0, 400))
    return np.quantile(_fractal_noise(u, v, 0), np.linspace(0.0, 1.0, 1001))


def coverage_threshold(coverage: float) -> float:
    """The density above which a point is cloudy, so that `coverage` of the plane is (0: none, 1: all)."""
    if coverage <= 0.0:
        return np.inf
    if coverage >= 1.0:
        return -np.inf
    quantiles = _density_quantiles()
    return float(np.interp(1.0 - coverage, np.linspace(0.0, 1.0, len(quantiles)), quantiles))


def cell_cloud(field: CloudField, level: int, i: int, j: int) -> Cloud | None:
    """The cloud of cell (level, i, j), or None where the cell is clear sky (`cell_clouds` of one cell)."""
    return cell_clouds(field, [(level, i, j)])[0]


def cell_clouds(field: CloudField, cells) -> list[Cloud | None]:
    """The cloud of each cell (level, i, j) of `cells`, or None where a cell is clear sky; each cell's the same
    whether it is made alone or with others (the work is done a level and a layer at a time, for all at once).

    A cloud's particles lie inside its cell's footprint and the field's extent,
    between the altitudes of `field.altitude`; its optics and colour are
    those of `field.cloud_type`.
    """
    cells = [tuple(int(v) for v in cell) for cell in cells]
    rows: list[list[np.ndarray]] = [[] for _ in cells]
    threshold = coverage_threshold(field.coverage)
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
        for layer in range(field.layers):
            chance = functools.partial(_chance, gx, gz, field.seed, level, layer)
            # displaced within their spacing, never out of the cell
            x = field.centre[0] + (gx + 0.5 + 0.8 * (chance(_JITTER_X) - 0.5)) * spacing
            z = field.centre[1] + (gz + 0.5 + 0.8 * (chance(_JITTER_Z) - 0.5)) * spacing
            density = cloud_density(field, x, z)
            headroom = (density - threshold) / max(1.0 - threshold, 1e-9) if np.isfinite(threshold) else density
            height = layer / field.layers
            kept = (density > threshold) & (headroom > TOP_HEADROOM * height)
            kept &= (np.abs(x - field.centre[0]) <= 0.5 * field.extent[0]) & (
                np.abs(z - field.centre[1]) <= 0.5 * field.extent[1]
            )
            if not kept.any():
                continue
            # the bottom layer sits flat on the condensation level; the others spread through their slab
            spread = 0.15 if layer == 0 else 0.8
            y = bottom + (layer + 0.5 + spread * (chance(_JITTER_Y) - 0.5)) * layer_depth
            radius = RADIUS_SPACINGS * spacing * (1.0 - TOP_SHRINK * height) * (0.8 + 0.4 * chance(_SIZE))
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


def _chance(gx: np.ndarray, gz: np.ndarray, seed: int, level: int, layer: int, purpose: int) -> np.ndarray:
    """A value in [0, 1) per candidate (gx, gz) of a level's plane, one hash seed per (field seed, level, layer,
    purpose) within hash01's 64 bits."""
    return hash01(gx, gz, (((seed * 1_000_003 + level) * 1_009 + layer) * 16 + purpose) & (2**64 - 1))
