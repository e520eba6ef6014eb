"""A density grid as particles whose splats reproduce it, and the error they leave.

A particle is the truth's blob of extinction (`cloudcore.measure.truth`): c K(|x - p| / r) with
c = tau / (r KERNEL_DIAMETER_INTEGRAL), so it holds tau r^2 KERNEL_VOLUME_INTEGRAL / KERNEL_DIAMETER_INTEGRAL
of extinction times volume.  A cloud has one optical depth tau for all its particles (`Cloud.optical_depth`),
so a particle's share of the density is set by its radius alone.

The fit, after Yusov's particle generation (2014, section 5.2: one particle per non-empty cell of a grid,
sized by the cloud's density in the cell): the grid's voxels are gathered into cubic blocks, the smallest (at
least MIN_BLOCK_VOXELS a side) that give at most the particle budget; each block with density becomes one
particle at its density's centroid, holding the block's integral of density.  tau is chosen so that a block
holding the REFERENCE_QUANTILE of the integrals gets a radius of one of FULL_BLOCK_RADII block sides (each
tried, the least error kept); thinner blocks get smaller radii, down to MIN_RADIUS.  A splat spreads its density
over its whole radius, which blurs the grid; REFINEMENTS passes then scale each particle's integral by what its
block holds over what the particles put there (a multiplicative deconvolution, a pass's result kept only where
it lowers the error).  docs/interop.md has the errors measured.

The error is measured against the grid: the particles' extinction sampled at every active voxel's centre
(`sampled_density`), and the integral the particles put outside the active voxels counted as error too:
relative L1 = (sum |sampled - grid| + outside) / sum grid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from cloudcore.maths.noise import hash01
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, KERNEL_VOLUME_INTEGRAL, splat_kernel
from cloudcore.measure.truth import peak_extinction
from cloudcore.scenes.interop.vdb import DensityGrid

#: the particle radii, in block sides, tried for a block whose integral is the REFERENCE_QUANTILE of the blocks'
#: (one per choice of the cloud's optical depth), the one leaving the least error kept.  A cloud has one optical
#: depth, and a particle's integral grows as its radius squared: a larger radius smooths a uniform region (2 was
#: best over the ball and the noise of `cloudcore.scenes.interop.example_grids`), a smaller one keeps the peaks of a
#: grid made of particles (1 was best over an exported scene's clouds); 0.9 as the quantile beat 0.7, 0.8 and 1
FULL_BLOCK_RADII = (0.7, 1.0, 1.4, 2.0)
REFERENCE_QUANTILE = 0.9
#: the smallest block side in voxels: a particle of a radius near one voxel is a spike at the voxel centre it
#: sits on and missed by the others (at 1.2 voxels a block the error doubled over 2)
MIN_BLOCK_VOXELS = 2.0
#: the smallest particle radius in block sides: a block too thin for it is left out or given a particle of this
#: radius by chance (keeping its integral on average), since a smaller particle's peak extinction, growing as
#: 1 / radius, would make a spike where it sits on a voxel
MIN_RADIUS = 0.6
#: deconvolution passes after the first fit (each costs one sampling of the particles at every voxel)
REFINEMENTS = 6
#: how far one pass may scale a particle's integral: a block whose particle misses every voxel centre
#: (a thin edge) would otherwise grow without bound
MAX_PASS_SCALE = 4.0
#: (particle, voxel) pairs one sampling chunk holds (memory: about 50 bytes each)
CHUNK_PAIRS = 4_000_000


@dataclass(frozen=True)
class ParticleFit:
    """Particle rows (x, y, z, radius) in the grid's world, the cloud's optical depth, the block side in
    voxels, and the relative L1 and L2 error of the particles' density against the grid's."""

    particles: np.ndarray
    optical_depth: float
    block: float
    relative_l1: float
    relative_l2: float


def fit_particles(grid: DensityGrid, max_particles: int, extinction_scale: float = 1.0) -> ParticleFit:
    """At most `max_particles` particles whose extinction reproduces `extinction_scale` times `grid`'s
    density (1/m per unit of density)."""
    if max_particles < 1:
        raise ValueError(f"the particle budget must be at least 1, got {max_particles}")
    density = grid.density * extinction_scale
    points = grid.world_points()
    block = _block_side(grid.voxels, max_particles)
    blocks, labels = np.unique(np.floor(grid.voxels / block).astype(np.int64), axis=0, return_inverse=True)
    labels = labels.reshape(-1)
    volume = grid.voxel_volume
    target = np.bincount(labels, density) * volume  # each block's integral of extinction
    centres = np.column_stack([np.bincount(labels, density * points[:, axis]) for axis in range(3)])
    centres /= target[:, None] / volume
    block_side = block * np.cbrt(volume)
    chance = hash01(blocks[:, 0], blocks[:, 1] * 2**21 + blocks[:, 2], 0)
    tree = cKDTree(points)
    best = None
    for full_radius in FULL_BLOCK_RADII:
        # the optical depth at which a block holding the REFERENCE_QUANTILE of the integrals gets full_radius
        reference = np.quantile(target, REFERENCE_QUANTILE)
        tau = float(reference / (full_radius * block_side) ** 2 * KERNEL_DIAMETER_INTEGRAL / KERNEL_VOLUME_INTEGRAL)
        smallest = particle_integral(MIN_RADIUS * block_side, tau)
        held = target.copy()
        for _ in range(REFINEMENTS + 1):
            # a block too thin for a particle of MIN_RADIUS gets one by chance, keeping its integral on average
            kept = np.maximum(held, smallest) * (chance < held / smallest)
            chosen = kept > 0.0
            radii = _radii(kept[chosen], tau)
            sampled = sampled_density(tree, centres[chosen], radii, tau, volume)
            l1, l2 = _errors(density, sampled, volume, kept[chosen])
            if best is None or l1 < best.relative_l1:
                best = ParticleFit(np.column_stack([centres[chosen], radii]), tau, block, l1, l2)
            inside = np.bincount(labels, sampled, len(target)) * volume
            held = held * np.clip(target / np.maximum(inside, 1e-300), 1.0 / MAX_PASS_SCALE, MAX_PASS_SCALE)
    return best


def _block_side(voxels: np.ndarray, max_particles: int) -> float:
    """The smallest block side (voxels, in steps of 5%, at least MIN_BLOCK_VOXELS) whose blocks holding
    active voxels are at most `max_particles`."""
    block = max(MIN_BLOCK_VOXELS, float(np.cbrt(len(voxels) / max_particles)))
    while len(np.unique(np.floor(voxels / block), axis=0)) > max_particles:
        block *= 1.05
    return block


def _radii(integrals: np.ndarray, tau: float) -> np.ndarray:
    """The radius at which a particle of optical depth `tau` holds each integral of extinction."""
    return np.sqrt(integrals * KERNEL_DIAMETER_INTEGRAL / (tau * KERNEL_VOLUME_INTEGRAL))


def particle_integral(radii, tau: float) -> np.ndarray:
    """The integral of extinction over volume that particles of `radii` and optical depth `tau` hold."""
    return tau * np.asarray(radii, dtype=np.float64) ** 2 * KERNEL_VOLUME_INTEGRAL / KERNEL_DIAMETER_INTEGRAL


def sampled_density(tree: cKDTree, centres: np.ndarray, radii: np.ndarray, tau: float, voxel_volume: float):
    """The particles' summed extinction at the points of `tree`, voxel centres of `voxel_volume` each (the
    truth's blobs, point sampled), in chunks of about CHUNK_PAIRS (particle, point) pairs."""
    peak = peak_extinction(tau, radii)
    count = tree.n
    total = np.zeros(count)
    pairs = np.cumsum(4.0 / 3.0 * np.pi * radii**3 / voxel_volume + 1.0)
    bounds = np.searchsorted(pairs, np.arange(CHUNK_PAIRS, pairs[-1] + CHUNK_PAIRS, CHUNK_PAIRS))
    for start, stop in zip(np.concatenate([[0], bounds[:-1]]), np.minimum(bounds, len(radii) - 1) + 1):
        neighbours = tree.query_ball_point(centres[start:stop], radii[start:stop], return_sorted=False)
        counts = np.fromiter((len(n) for n in neighbours), dtype=np.int64, count=len(neighbours))
        if not counts.sum():
            continue
        point = np.concatenate([np.asarray(n, dtype=np.int64) for n in neighbours if n])
        particle = np.repeat(np.arange(start, stop), counts)
        distance = np.linalg.norm(tree.data[point] - centres[particle], axis=1) / radii[particle]
        total += np.bincount(point, peak[particle] * splat_kernel(distance), count)
    return total


def _errors(density: np.ndarray, sampled: np.ndarray, volume: float, integrals: np.ndarray) -> tuple[float, float]:
    """(relative L1, relative L2) of `sampled` against `density` at the active voxels, the L1 with the
    particles' integral that falls outside them (their whole integral less what the voxels sampled)."""
    outside = max(0.0, float(integrals.sum()) - float(sampled.sum()) * volume)
    l1 = (float(np.abs(sampled - density).sum()) * volume + outside) / (float(density.sum()) * volume)
    l2 = float(np.sqrt(np.sum((sampled - density) ** 2) / np.sum(density**2)))
    return l1, l2
