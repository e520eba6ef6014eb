"""Overdraw: how many splat fragments land on each pixel, measured and estimated (numpy).

The GL side counts blended fragments per pixel (`FrameRenderer.measure_overdraw`);
this module turns those counts into the reported numbers (their heat map is
`cloudcore.stats.heatmap`), beside the analytic estimate Harris and Wang reason with
(`cloudcore.lod.splat_coverage`, whose `splats_in_view` the frame plan prices near units with).

Wang's "cloud block overdraw" (2004, section 6.3) is the view-independent
counterpart: the summed sprite areas in each ground block over the block's
area (`cloud_block_overdraw`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Overdraw:
    """Fragments blended per pixel by the frame's cloud pass (counted), and the analytic estimate."""

    mean: float  # over the screen
    mean_covered: float  # over the pixels any splat covers
    max: float
    analytic: float  # summed splat disc areas over the screen's (`cloudcore.lod.splat_coverage.analytic_overdraw`)


def overdraw_statistics(counts: np.ndarray, analytic: float) -> Overdraw:
    """Mean over the screen, mean over covered pixels, and maximum of a per-pixel fragment count, beside the
    `analytic` estimate."""
    covered = counts > 0
    return Overdraw(
        mean=float(counts.mean()) if counts.size else 0.0,
        mean_covered=float(counts[covered].mean()) if covered.any() else 0.0,
        max=float(counts.max()) if counts.size else 0.0,
        analytic=analytic,
    )


#: Wang's cloud blocks are 16 square kilometres: 4 km on a side
WANG_BLOCK_SIZE_M = 4000.0


def cloud_block_overdraw(
    centres: np.ndarray, radii: np.ndarray, block_size: float = WANG_BLOCK_SIZE_M
) -> tuple[np.ndarray, np.ndarray]:
    """(blocks (k, 2), overdraw (k,)) of the non-empty ground blocks (Wang 2004, section 6.3).

    The ground (x, z; y is up) is cut into squares of side `block_size`
    aligned with the origin; block (i, j) covers x in [i s, (i + 1) s) and z in
    [j s, (j + 1) s), and holds the particles whose centres fall in it.  Its
    overdraw is the sum of their splat disc areas, pi r^2, over s^2.  Rows are
    sorted by (i, j); i and j are whole numbers stored as float64.
    """
    if not (np.isfinite(block_size) and block_size > 0):
        raise ValueError(f"block_size must be finite and > 0, got {block_size}")
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    if len(radii) != len(centres):
        raise ValueError(f"{len(centres)} centres but {len(radii)} radii")
    blocks, block_of = np.unique(np.floor(centres[:, [0, 2]] / block_size), axis=0, return_inverse=True)
    # radius over block size before squaring: no overflow for sprites far smaller than the float range
    area_fraction = np.pi * (radii / block_size) ** 2
    overdraw = np.bincount(block_of.reshape(-1), weights=area_fraction, minlength=len(blocks))
    return blocks, overdraw.astype(np.float64, copy=False)  # bincount of no particles is integer


def cloud_block_overdraw_statistics(overdraw: np.ndarray) -> dict:
    """Maximum and mean of the non-empty blocks' overdraw, and how many there are."""
    return {
        "block_overdraw_max": float(overdraw.max()) if overdraw.size else 0.0,
        "block_overdraw_mean": float(overdraw.mean()) if overdraw.size else 0.0,
        "blocks": int(overdraw.size),
    }


def scene_block_overdraw_statistics(clouds, block_size: float = WANG_BLOCK_SIZE_M) -> dict:
    """`cloud_block_overdraw_statistics` over every particle of `clouds`."""
    particles = np.concatenate([c.particles for c in clouds]) if clouds else np.zeros((0, 4))
    return cloud_block_overdraw_statistics(cloud_block_overdraw(particles[:, :3], particles[:, 3], block_size)[1])
