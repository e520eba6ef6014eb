"""OpenVDB import and export (issue 56): grids made with tinyvdb imported as particles whose density matches
within the stated error, scenes' clouds exported and read back, and every bad file refused with one line and
exit status 2, the scene untouched."""

import dataclasses
import struct

import numpy as np
import pytest
from scipy.spatial import cKDTree

from cloudcore.cli import main
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import NEW_SCENE_SHADING, Cloud, Scene, Shading
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.interop import vdb
from cloudcore.scenes.interop.density_fit import fit_particles, particle_integral, sampled_density
from cloudcore.scenes.interop.example_grids import noise_grid, sphere_grid
from cloudcore.scenes.interop.vdb import DensityGrid, read_density_grids, write_density_grids
from cloudcore.scenes.interop.vdb_clouds import cloud_density_grids, import_vdb_clouds

#: the density errors docs/interop.md states (`cloudview import` prints them), with a margin of rounding
SPHERE_L1, NOISE_L1 = 0.10, 0.20


def resampled_error(grid: DensityGrid, particles: np.ndarray, tau: float) -> float:
    """Relative L1 of the particles' extinction at the grid's voxel centres against the grid's, measured
    apart from the fit's own bookkeeping (the particles' integral outside the voxels counted as error)."""
    sampled = sampled_density(cKDTree(grid.world_points()), particles[:, :3], particles[:, 3], tau, grid.voxel_volume)
    outside = particle_integral(particles[:, 3], tau).sum() - sampled.sum() * grid.voxel_volume
    return (np.abs(sampled - grid.density).sum() * grid.voxel_volume + max(outside, 0.0)) / (
        grid.density.sum() * grid.voxel_volume
    )


@pytest.mark.parametrize("grid, bound", [(sphere_grid(), SPHERE_L1), (noise_grid(), NOISE_L1)], ids=["sphere", "noise"])
def test_an_imported_grid_is_particles_whose_density_matches_it(tmp_path, grid, bound):
    write_density_grids(tmp_path / "grid.vdb", [grid])
    (read,) = read_density_grids(tmp_path / "grid.vdb")
    order, read_order = np.lexsort(grid.voxels.T), np.lexsort(read.voxels.T)  # tinyvdb gives them leaf by leaf
    np.testing.assert_allclose(read.world_points()[read_order], grid.world_points()[order])
    np.testing.assert_allclose(read.density[read_order], grid.density[order], rtol=1e-6)  # float32 in the file
    fit = fit_particles(read, 4000)
    assert len(fit.particles) <= 4000
    error = resampled_error(grid, fit.particles, fit.optical_depth)
    assert error == pytest.approx(fit.relative_l1, rel=1e-6) and error < bound  # float32 in the file
    # the particles carry the grid's integral: what a block holds, not its peak, is fitted
    total = particle_integral(fit.particles[:, 3], fit.optical_depth).sum()
    assert total == pytest.approx(grid.density.sum() * grid.voxel_volume, rel=0.25)


def test_a_smaller_budget_gives_fewer_particles_and_more_error():
    grid = sphere_grid()
    coarse, fine = fit_particles(grid, 300), fit_particles(grid, 4000)
    assert len(coarse.particles) <= 300 < len(fine.particles)
    assert coarse.relative_l1 > fine.relative_l1


def test_a_rotated_sheared_transform_places_the_particles_in_the_world(tmp_path):
    """Any affine transform: the fit works on the voxels' world centres, and the error stays that of the
    axis-aligned grid (the same density, moved)."""
    grid = sphere_grid(side=16, voxel=20.0)
    angle = np.radians(30.0)
    rotation = np.array([[np.cos(angle), 0.0, -np.sin(angle)], [0.0, 1.0, 0.0], [np.sin(angle), 0.0, np.cos(angle)]])
    turned = DensityGrid("turned", grid.voxels, grid.density, grid.linear @ rotation, np.array([500.0, 0.0, 0.0]))
    straight, rotated = fit_particles(grid, 500), fit_particles(turned, 500)
    centre = np.average(rotated.particles[:, :3], axis=0, weights=rotated.particles[:, 3] ** 2)
    expected = np.average(turned.world_points(), axis=0, weights=turned.density)
    np.testing.assert_allclose(centre, expected, atol=5.0)
    assert rotated.relative_l1 == pytest.approx(straight.relative_l1, abs=0.03)


def test_several_grids_become_several_clouds_within_one_budget(tmp_path):
    path = tmp_path / "two.vdb"
    write_density_grids(path, [sphere_grid(side=16, name="a"), sphere_grid(side=16, name="b", centre=(900, 1000, 0))])
    imported = import_vdb_clouds(path, 600, taken_names=["a"])
    assert [item.cloud.name for item in imported] == ["a-2", "b"]
    assert sum(len(item.cloud.particles) for item in imported) <= 600
    assert all(item.cloud.optical_depth == item.fit.optical_depth for item in imported)


def test_cli_import_into_a_new_scene_then_an_existing_one(tmp_path, capsys):
    write_density_grids(tmp_path / "ball.vdb", [sphere_grid(name="../../ball")])
    scene_path = tmp_path / "scene.toml"
    assert main(["import", str(tmp_path / "ball.vdb"), "--out", str(scene_path), "--particles", "2000"]) == 0
    out = capsys.readouterr().out
    assert "density error L1" in out and "wrote" in out
    scene = load_scene(scene_path)
    (cloud,) = scene.clouds
    # a hostile grid name stays a name: its particles are in the scene's own folder
    assert (tmp_path / cloud.particles_file).resolve().parent == (tmp_path / "scene.particles").resolve()
    assert scene.shading == NEW_SCENE_SHADING != Shading()  # a new scene's, kept in its file
    save_scene(dataclasses.replace(scene, shading=Shading()), scene_path)
    assert main(["import", str(tmp_path / "ball.vdb"), "--out", str(scene_path), "--particles", "2000"]) == 0
    again = load_scene(scene_path)
    assert [c.name for c in again.clouds] == ["../../ball", "../../ball-2"]
    assert again.shading == Shading()  # an existing scene keeps its own


def two_cloud_scene() -> Scene:
    rng = np.random.default_rng(3)

    def puff(centre, count):
        return np.column_stack([rng.normal(size=(count, 3)) * 60.0 + centre, np.full(count, 40.0)])

    return Scene(
        clouds=(Cloud("west", puff((-400, 900, 0), 40)), Cloud("east", puff((400, 950, 0), 30), optical_depth=3.0))
    )


def test_export_then_import_round_trip_of_a_scenes_clouds(tmp_path, capsys):
    scene = two_cloud_scene()
    save_scene(scene, tmp_path / "puffs.toml")
    out = tmp_path / "puffs.vdb"
    assert main(["export", str(tmp_path / "puffs.toml"), "--out", str(out), "--voxels-per-radius", "3"]) == 0
    grids = read_density_grids(out)
    assert [g.name for g in grids] == ["west", "east"]
    expected = cloud_density_grids(scene, voxels_per_radius=3.0)
    for grid, direct in zip(grids, expected):
        order, read_order = np.lexsort(direct.voxels.T), np.lexsort(grid.voxels.T)
        np.testing.assert_allclose(grid.world_points()[read_order], direct.world_points()[order], atol=1e-9)
        np.testing.assert_allclose(grid.density[read_order], direct.density[order], rtol=1e-6)
        # the exported extinction is the clouds' own: each particle's tau is the line integral through it
        assert grid.density.sum() * grid.voxel_volume == pytest.approx(
            sum(particle_integral(c.radii, c.optical_depth or 8.0).sum() for c in scene.clouds if c.name == grid.name),
            rel=0.1,
        )
    capsys.readouterr()
    assert main(["import", str(out), "--out", str(tmp_path / "back.toml"), "--particles", "2000"]) == 0
    back = load_scene(tmp_path / "back.toml")
    assert [c.name for c in back.clouds] == ["west", "east"]
    for grid, cloud in zip(grids, back.clouds):
        # docs/interop.md: 38% and 41% (an exported grid is the peaks of particles 3 voxels a radius, and a fitted
        # particle is at least 2 voxels a block, blurring them)
        assert resampled_error(grid, cloud.particles, cloud.optical_depth) < 0.45


def test_export_merged_is_one_density_grid(tmp_path):
    scene = two_cloud_scene()
    (merged,) = cloud_density_grids(scene, merged=True, voxels_per_radius=1.2)
    apart = cloud_density_grids(scene, voxels_per_radius=1.2)
    assert merged.name == "density"
    total = sum(g.density.sum() for g in apart)
    assert merged.density.sum() == pytest.approx(total, rel=0.01)  # another lattice of the same voxel size


# ---------------------------------------------------------------- bad files: one line, exit 2, nothing written


def patched(data: bytes, old: bytes, new: bytes) -> bytes:
    """`data` with the first `old` (the map's scale, ahead of its voxel size) made `new`."""
    assert old in data
    return data.replace(old, new, 1)


def bad_files(folder):
    """(name, bytes) of each hostile file, made from a good one."""
    good_path = folder / "good.vdb"
    write_density_grids(good_path, [sphere_grid(side=8, voxel=10.0)])
    good = good_path.read_bytes()
    scale = struct.pack("<3d", 10.0, 10.0, 10.0)
    with_nan = sphere_grid(side=8, voxel=10.0)
    density = with_nan.density.copy()
    density[5] = np.nan
    write_density_grids(
        folder / "nan_source.vdb",
        [DensityGrid("sphere", with_nan.voxels, density, with_nan.linear, with_nan.translation)],
    )
    return {
        "truncated": good[: len(good) // 2],
        "not a VDB": b"# a scene, not a volume\n" * 10,
        "NaN density": (folder / "nan_source.vdb").read_bytes(),
        "absurd transform": patched(good, scale, struct.pack("<3d", 1e300, 10.0, 10.0)),
        "singular transform": patched(good, scale, struct.pack("<3d", 0.0, 10.0, 10.0)),
    }


@pytest.mark.parametrize(
    "case, words",
    [
        ("truncated", "not a readable OpenVDB file"),
        ("not a VDB", "not a readable OpenVDB file"),
        ("NaN density", "density must be finite"),
        ("absurd transform", "past +-"),
        ("singular transform", "singular"),
        ("missing", "no such file"),
        ("too many voxels", "active voxels, at most 100"),
    ],
)
def test_a_bad_file_is_refused_with_one_line_and_exit_2(tmp_path, capsys, monkeypatch, case, words):
    files = bad_files(tmp_path)
    path = tmp_path / f"{case}.vdb"
    if case == "too many voxels":
        monkeypatch.setattr(vdb, "MAX_GRID_VOXELS", 100)  # a grid of 10^12 voxels, without making one
        path = tmp_path / "good.vdb"
    elif case != "missing":
        path.write_bytes(files[case])
    scene_path = tmp_path / "scene.toml"
    save_scene(two_cloud_scene(), scene_path)
    before = scene_path.read_bytes()
    capsys.readouterr()
    assert main(["import", str(path), "--out", str(scene_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert str(path) in err and words in err
    assert scene_path.read_bytes() == before  # nothing half imported


def test_a_grid_tinyvdb_reads_only_in_part_is_refused(tmp_path):
    """tinyvdb 0.9.0 drops the leaves past a tree's 64th: a 40^3 grid (125 leaves) is refused, not cut."""
    side = 40
    index = np.indices((side,) * 3).reshape(3, -1).T
    write_density_grids(
        tmp_path / "wide.vdb", [DensityGrid("wide", index, np.ones(len(index)), np.eye(3), np.zeros(3))]
    )
    with pytest.raises(SceneError, match="read only 32,768 of its 64,000"):
        read_density_grids(tmp_path / "wide.vdb")


def test_export_of_a_scene_without_clouds_is_refused(tmp_path, capsys):
    save_scene(Scene(), tmp_path / "empty.toml")
    assert main(["export", str(tmp_path / "empty.toml"), "--out", str(tmp_path / "x.vdb")]) == 2
    assert "no cloud" in capsys.readouterr().err
    assert not (tmp_path / "x.vdb").exists()
