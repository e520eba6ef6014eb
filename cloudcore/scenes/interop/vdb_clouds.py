"""Clouds in and out of OpenVDB files: each float grid of a file becomes a cloud of fitted particles
(`cloudcore.scenes.interop.density_fit`), and a scene's clouds become extinction grids (one per cloud, or one
merged), sampled as the path-traced truth samples them (`cloudcore.measure.truth`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.light.illumination import cloud_optics
from cloudcore.measure.truth import DEFAULT_VOXELS_PER_RADIUS, peak_extinction, splat_grid_box, splatted_extinction
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Cloud, Scene
from cloudcore.scenes.interop.density_fit import ParticleFit, fit_particles
from cloudcore.scenes.interop.vdb import DensityGrid, read_density_grids, write_density_grids
from cloudcore.scenes.limits import MAX_NAME_LENGTH

#: particles of all the clouds of one imported file, unless asked otherwise (the default scene has 90,000)
DEFAULT_PARTICLES = 20_000
#: the name of a merged export's grid: the one Blender's and Houdini's volume shaders read by default
MERGED_GRID_NAME = "density"


@dataclass(frozen=True)
class ImportedCloud:
    """A cloud made from a grid, and the fit that made it (its error)."""

    cloud: Cloud
    fit: ParticleFit
    grid: DensityGrid


def import_vdb_clouds(
    path, max_particles: int = DEFAULT_PARTICLES, extinction_scale: float = 1.0, taken_names=()
) -> list[ImportedCloud]:
    """A cloud for each float grid with density in the OpenVDB file at `path`, at most `max_particles`
    particles in all (shared by the grids as their active voxels), named after its grid and unlike
    `taken_names`.  `extinction_scale`: extinction (1/m) per unit of the file's density.  SceneError for a
    file that cannot be imported; nothing is returned in part."""
    if not (np.isfinite(extinction_scale) and extinction_scale > 0.0):
        raise SceneError(str(path), "--extinction", f"must be a finite number > 0, got {extinction_scale}")
    grids = read_density_grids(path)
    if max_particles < len(grids):
        raise SceneError(str(path), "--particles", f"{len(grids)} grids need at least {len(grids)} particles")
    voxels = np.array([len(grid.density) for grid in grids], dtype=np.float64)
    budgets = np.maximum(1, np.floor(max_particles * voxels / voxels.sum())).astype(int)
    taken = set(taken_names)
    imported = []
    for grid, budget in zip(grids, budgets):
        fit = fit_particles(grid, int(budget), extinction_scale)
        name = free_name(grid.name or "vdb", taken)
        taken.add(name)
        cloud = Cloud(name=name, particles=fit.particles, optical_depth=fit.optical_depth)
        imported.append(ImportedCloud(cloud, fit, grid))
    return imported


def free_name(wanted: str, taken) -> str:
    """`wanted` cut to a name's length, with a number after it where something has that name already (a cloud,
    a camera path: the names in `taken`)."""
    name = wanted[:MAX_NAME_LENGTH]
    number = 2
    while name in taken:
        suffix = f"-{number}"
        name = wanted[: MAX_NAME_LENGTH - len(suffix)] + suffix
        number += 1
    return name


def export_vdb(scene: Scene, path, merged: bool = False, voxels_per_radius: float = DEFAULT_VOXELS_PER_RADIUS):
    """Write the scene's clouds to the OpenVDB file at `path` (atomically) as extinction grids (1/m, in
    metres): one per cloud named as the cloud, or with `merged` one named MERGED_GRID_NAME; return them."""
    grids = cloud_density_grids(scene, merged, voxels_per_radius)
    write_density_grids(path, grids)
    return grids


def cloud_density_grids(
    scene: Scene, merged: bool = False, voxels_per_radius: float = DEFAULT_VOXELS_PER_RADIUS
) -> list[DensityGrid]:
    """The clouds' extinction at the centres of cubic voxels of the scene's median particle radius /
    `voxels_per_radius` (one voxel size for all, so merged or not the grids agree), the voxels with
    extinction kept.  SceneError where the scene has no clouds to export or a grid would be too large."""
    if not (np.isfinite(voxels_per_radius) and voxels_per_radius > 0.0):
        raise SceneError("--voxels-per-radius", "value", f"must be a finite number > 0, got {voxels_per_radius}")
    parts = []
    for cloud in scene.clouds:
        tau, albedo = cloud_optics(cloud, scene.shading)
        keep = (cloud.radii > 0) & (tau > 0)
        if keep.any():
            parts.append((cloud.name, cloud.centres[keep], cloud.radii[keep], tau[keep], albedo[keep]))
    if not parts:
        raise SceneError("export", "clouds", "the scene has no cloud with particles to export")
    voxel = float(np.median(np.concatenate([part[2] for part in parts]))) / voxels_per_radius
    if merged:
        parts = [(MERGED_GRID_NAME, *(np.concatenate(column) for column in list(zip(*parts))[1:]))]
    return [_grid(name, voxel, centres, radii, tau, albedo) for name, centres, radii, tau, albedo in parts]


def _grid(name: str, voxel: float, centres, radii, tau, albedo) -> DensityGrid:
    try:
        low, shape_xyz = splat_grid_box(centres, radii, voxel)
    except ValueError as error:
        raise SceneError("--voxels-per-radius", name, str(error)) from None
    extinction, _ = splatted_extinction(low, voxel, shape_xyz, centres, radii, peak_extinction(tau, radii), albedo)
    z, y, x = np.nonzero(extinction)
    return DensityGrid(
        name=name,
        voxels=np.column_stack([x, y, z]).astype(np.int64),
        density=extinction[z, y, x],
        linear=np.eye(3) * voxel,
        translation=low + 0.5 * voxel,  # the truth's voxel (i, j, k) is centred at low + (i + 0.5) * voxel
    )
