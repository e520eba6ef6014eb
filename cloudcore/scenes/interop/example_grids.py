"""Density grids to import: a ball with a soft edge and a cloud of noise, what the tests, the editor's GUI test
and `scripts/make_vdb_examples.py` write as .vdb files.  Each is at most 32^3 voxels (64 leaves of 8^3),
within what tinyvdb 0.9.0 reads back whole (`cloudcore.scenes.interop.vdb`)."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter

from cloudcore.maths.noise import hash01
from cloudcore.scenes.interop.vdb import DensityGrid

#: the examples' extinction inside (1/m): a 600 m cloud of it is some 30 deep, opaque at its centre
EXAMPLE_EXTINCTION = 0.05


def sphere_grid(side: int = 32, voxel: float = 20.0, centre=(0.0, 1000.0, 0.0), name: str = "sphere") -> DensityGrid:
    """A ball of EXAMPLE_EXTINCTION filling 80% of a cube of `side` voxels, falling linearly to 0 over its
    outer 25% of radius."""
    index = np.indices((side,) * 3).reshape(3, -1).T
    distance = np.linalg.norm(index - (side - 1) / 2.0, axis=1) / (0.4 * side)
    density = EXAMPLE_EXTINCTION * np.clip((1.0 - distance) / 0.25, 0.0, 1.0)
    return _grid(name, index, density, voxel, centre, side)


def noise_grid(side: int = 32, voxel: float = 20.0, centre=(0.0, 1000.0, 0.0), seed: int = 1) -> DensityGrid:
    """Smoothed value noise (features of a few voxels) inside a flattened ellipsoid: a cumulus-like blob."""
    index = np.indices((side,) * 3).reshape(3, -1).T
    white = hash01(index[:, 0], index[:, 1] * side + index[:, 2], seed).reshape((side,) * 3) - 0.5
    smooth = gaussian_filter(white, 2.0).reshape(-1)
    smooth /= smooth.std()
    shape = 1.0 - np.linalg.norm((index - (side - 1) / 2.0) / (side * np.array([0.45, 0.3, 0.45])), axis=1)
    density = EXAMPLE_EXTINCTION * np.clip(0.5 * smooth + 1.5 * shape, 0.0, None)
    return _grid("noise", index, density, voxel, centre, side)


def _grid(name, index, density, voxel, centre, side) -> DensityGrid:
    keep = density > 0.0
    corner = np.asarray(centre, dtype=np.float64) - voxel * (side - 1) / 2.0
    return DensityGrid(name, index[keep], density[keep], np.eye(3) * voxel, corner)
