"""The truth's medium without Mitsuba: the particles' extinction grid, its line integrals, the regions."""

import itertools
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from cloudcore.light.lighting import sky_gradient
from cloudcore.light.phase import phase_function
from cloudcore.maths.colour import srgb_decode, srgb_encode
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, SPLAT_SHARPNESS
from cloudcore.measure.truth import medium_grids, optical_depths, peak_extinction, phase_description, resolution_gain
from cloudcore.measure.truth_comparison import luminance, region_errors, truth_regions
from cloudcore.model.scene import Camera, Cloud, Scene, Shading
from cloudcore.world.camera import pixel_rays, projection_matrix, view_matrix


def one_particle(tau, radius=50.0, centre=(0.0, 1000.0, 0.0), albedo=0.9) -> Scene:
    return Scene(shading=Shading(albedo=albedo, optical_depth=tau), clouds=(Cloud("one", [[*centre, radius]]),))


def test_the_kernel_integral_is_the_closed_form():
    # K(u) = (exp(-s u^2) - e^-s) / (1 - e^-s) on [0, 1]; its integral has erf in it
    s, floor = SPLAT_SHARPNESS, math.exp(-SPLAT_SHARPNESS)
    half = (0.5 * math.sqrt(math.pi / s) * math.erf(math.sqrt(s)) - floor) / (1.0 - floor)
    assert KERNEL_DIAMETER_INTEGRAL == pytest.approx(2.0 * half, rel=1e-14)
    assert peak_extinction(8.0, 50.0) == pytest.approx(8.0 / (50.0 * 2.0 * half), rel=1e-14)


@pytest.mark.parametrize("tau", [0.05, 1.0, 8.0, 300.0])
@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (3.1, -7.7, 1.9)])
@pytest.mark.parametrize("voxels_per_radius", [3.0, 6.0])
def test_the_grid_s_optical_depth_through_a_particle_s_centre_is_its_tau(tau, offset, voxels_per_radius):
    centre = np.array([10.0, 1000.0, -20.0]) + offset
    grids = medium_grids(one_particle(tau, centre=tuple(centre)), voxels_per_radius)
    assert len(grids) == 1
    directions = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 1.0, 1.0], [0.3, -0.2, 0.9]])
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    depth, _ = optical_depths(grids, centre - 500.0 * directions, directions)
    # sampled at voxel centres and interpolated, with the resolution gain: within 5.5% at 3 voxels a radius
    # (the worst: a centre on a voxel corner, a ray along an axis), 2% at 6
    tolerance = 0.055 if voxels_per_radius == 3.0 else 0.02
    np.testing.assert_allclose(depth, tau, rtol=tolerance)


@pytest.mark.parametrize("voxels_per_radius, worst", [(3.0, 0.045), (4.0, 0.025), (6.0, 0.009)])
def test_over_random_centres_and_directions_the_grid_keeps_tau_on_average(voxels_per_radius, worst):
    rng = np.random.default_rng(1)
    directions = rng.normal(size=(20, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    errors = []
    for _ in range(8):
        centre = np.array([0.0, 1000.0, 0.0]) + rng.uniform(0.0, 20.0, 3)
        grids = medium_grids(one_particle(1.0, centre=tuple(centre)), voxels_per_radius)
        errors.append(optical_depths(grids, centre - 400.0 * directions, directions)[0] - 1.0)
    errors = np.concatenate(errors)
    assert abs(errors.mean()) < 0.002 and np.abs(errors).max() < worst


def test_without_the_resolution_gain_interpolation_loses_optical_depth():
    # the losses resolution_gain was fitted to; its inverse at 3, 4, 6 and 8 voxels a radius
    np.testing.assert_allclose(1.0 / resolution_gain([3.0, 4.0, 6.0, 8.0]), [0.836, 0.907, 0.958, 0.977], atol=0.005)


def test_off_centre_rays_see_less_and_rays_past_the_radius_see_nothing():
    grids = medium_grids(one_particle(8.0), 6.0)
    impact = np.array([0.0, 10.0, 25.0, 40.0, 52.0, 200.0])  # metres from the centre; radius 50
    origins = np.column_stack([np.full(6, -400.0), 1000.0 + impact, np.zeros(6)])
    depth, unit = optical_depths(grids, origins, np.tile([1.0, 0.0, 0.0], (6, 1)))
    assert np.all(np.diff(depth) <= 0) and depth[0] == pytest.approx(8.0, rel=0.02)
    # interpolation spreads the kernel's edge over a voxel: a little past the radius, nothing a voxel past it
    assert depth[-1] == 0.0 and depth[-2] < 0.03
    # optical depth 1 is reached inside the near half of the particle, never where the depth stays below 1
    assert 400.0 - 50.0 < unit[0] < 400.0 and np.isinf(unit[-1])


def test_the_medium_is_cut_into_bricks_that_leave_the_air_between_clouds_out():
    scene = Scene(clouds=(Cloud("a", [[0.0, 1000.0, 0.0, 50.0]]), Cloud("far", [[3000.0, 1000.0, 0.0, 50.0]])))
    bricks = medium_grids(scene, 3.0)
    # a particle 100 m across at 16.7 m voxels fits in 2 x 2 x 2 bricks of 16 voxels (267 m)
    assert 2 <= len(bricks) <= 16
    assert all(brick.extinction.any() for brick in bricks)
    assert not any(500.0 < brick.box_low[0] < 2500.0 for brick in bricks)
    # the boxes do not overlap, and each brick's data reach one voxel past its box (where there is more grid)
    for a, b in itertools.combinations(bricks, 2):
        assert np.any(a.box_high <= b.box_low) or np.any(b.box_high <= a.box_low)
    depth, _ = optical_depths(bricks, [[-500.0, 1000.0, 0.0]], [[1.0, 0.0, 0.0]])
    assert depth[0] == pytest.approx(2 * 8.0, rel=0.055)  # centres on voxel corners, along an axis: the worst


def test_albedo_is_the_extinction_weighted_mean_and_overlaps_add_extinction():
    both = [[0.0, 1000.0, 0.0, 50.0]]
    scene = Scene(
        shading=Shading(optical_depth=2.0),
        clouds=(Cloud("dark", both, albedo=0.5), Cloud("bright", both, albedo=1.0, optical_depth=6.0)),
    )
    (grid,) = medium_grids(scene, 4.0)
    inside = grid.extinction > 0
    np.testing.assert_allclose(grid.albedo[inside], (0.5 * 2.0 + 1.0 * 6.0) / 8.0)
    depth, _ = optical_depths([grid], [[-300.0, 1000.0, 0.0]], [[1.0, 0.0, 0.0]])
    assert depth[0] == pytest.approx(8.0, rel=0.035)


def test_a_medium_past_the_voxel_limit_is_refused():
    with pytest.raises(ValueError, match="voxels"):
        medium_grids(one_particle(1.0), 2000.0)


def test_no_particles_no_grids_and_nothing_to_see():
    assert medium_grids(Scene()) == []
    depth, unit = optical_depths([], np.zeros((3, 3)), np.tile([0.0, 0.0, 1.0], (3, 1)))
    assert np.all(depth == 0) and np.all(np.isinf(unit))


def test_pixel_rays_go_through_the_pixel_centres_of_the_projection():
    camera = Camera((100.0, 400.0, 2000.0), (-300.0, 900.0, 0.0), 50.0)
    width, height = 7, 5
    rays = pixel_rays(camera, width, height)
    clip = projection_matrix(camera.fov_y_deg, width / height) @ view_matrix(camera)
    points = np.asarray(camera.position) + 100.0 * rays.reshape(-1, 3)
    projected = clip @ np.column_stack([points, np.ones(len(points))]).T
    ndc = (projected[:2] / projected[3]).T.reshape(height, width, 2)
    columns, rows = np.meshgrid(np.arange(width), np.arange(height))
    np.testing.assert_allclose(ndc[..., 0], (columns + 0.5) / width * 2 - 1, atol=1e-12)
    np.testing.assert_allclose(ndc[..., 1], 1 - (rows + 0.5) / height * 2, atol=1e-12)  # top row first
    forward = np.subtract(camera.look_at, camera.position)
    np.testing.assert_allclose(rays[2, 3], forward / np.linalg.norm(forward), atol=1e-12)


def test_the_sky_gradient_is_the_world_pass_s():
    zenith, horizon = np.array([0.1, 0.2, 0.7]), np.array([0.6, 0.6, 0.8])
    rays = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.25, np.sqrt(1 - 0.0625)]])
    np.testing.assert_allclose(
        sky_gradient(rays, zenith, horizon), [zenith, horizon, horizon, 0.5 * (zenith + horizon)]
    )


def test_srgb_decode_undoes_encode():
    linear = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(srgb_decode(srgb_encode(linear)), linear, atol=1e-12)


def test_a_phase_function_mitsuba_lacks_goes_in_as_our_own_table():
    assert phase_description("rayleigh", 0.0) == {"type": "rayleigh"}
    assert phase_description("henyey-greenstein", 0.8) == {"type": "hg", "g": 0.8}
    table = phase_description("cornette-shanks", 0.7)
    values = np.array([float(v) for v in table["values"].split(",")])
    assert table["type"] == "tabphase"
    np.testing.assert_allclose(values[[0, -1]], phase_function(np.array([-1.0, 1.0]), "cornette-shanks", 0.7), 1e-8)


def test_regions_split_the_image_by_the_truth_s_alpha_and_sun_depth():
    alpha = np.array([[0.0, 0.01, 0.5], [0.95, 0.99, 1.0]])
    sun_depth = np.array([[np.inf, np.inf, 0.2], [0.5, 3.0, np.inf]])
    regions = truth_regions(alpha, sun_depth)
    assert regions["sky"].tolist() == [[True, True, False], [False, False, False]]
    assert regions["silhouette"].tolist() == [[False, False, True], [False, False, False]]
    assert regions["lit"].tolist() == [[False, False, False], [True, False, False]]
    assert regions["shadowed"].tolist() == [[False, False, False], [False, True, True]]
    assert regions["image"].all()


def test_region_errors_sign_the_luminance_error():
    truth = np.full((2, 3, 3), 100, dtype=np.uint8)
    brighter = truth + np.uint8(20)
    regions = truth_regions(np.array([[0.0, 0.5, 1.0], [1.0, 1.0, 1.0]]), np.zeros((2, 3)))
    same = region_errors(truth, truth, regions)
    assert same["image"]["psnr_db"] == 100.0 and same["image"]["mean_luminance_error"] == 0.0
    errors = region_errors(truth, brighter, regions)
    assert errors["lit"]["pixels"] == 4 and errors["lit"]["mean_luminance_error"] > 0
    assert errors["lit"]["truth_luminance"] == pytest.approx(luminance(truth[0, 0]))
    assert errors["shadowed"] == {"pixels": 0}
    assert errors["sky"]["psnr_db"] == pytest.approx(20 * math.log10(255 / 20))


def test_cloudview_truth_without_mitsuba_is_one_line_and_exit_2(tmp_path):
    # a `mitsuba` module that cannot be imported stands in for a machine without the truth extra
    (tmp_path / "mitsuba.py").write_text("raise ImportError('not here')\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "truth", "--out", str(tmp_path / "t.png")],
        capture_output=True,
        text=True,
        env=env,
    )
    assert result.returncode == 2
    assert result.stderr.strip() == (
        "cloudview: error: cloudview truth: mitsuba: not installed (pip install 'cloudview[truth]')"
    )


def test_cloudview_truth_refuses_a_bad_look_for_its_models_in_one_line_before_tracing(tmp_path):
    pytest.importorskip("mitsuba")
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "truth", "--out", str(tmp_path / "t.png"), "--detail-noise", "2"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and not (tmp_path / "t.png").exists()
    assert result.stderr.strip() == (
        "cloudview: error: cloudview truth: settings: detail_noise must be within [0, 1], got 2.0"
    )
