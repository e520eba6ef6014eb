"""Overdraw: the fragment counter against geometry we can count by hand, and the analytic estimate."""

import numpy as np
import pytest

from cloudcore.lod.splat_coverage import (
    analytic_overdraw,
    splats_in_frustum,
    splats_in_view,
    splats_in_view_per_set,
)
from cloudcore.model.scene import Camera, Cloud, Scene
from cloudcore.model.settings import FULL_3D
from cloudcore.stats.overdraw import Overdraw, overdraw_statistics
from cloudcore.world.camera import FAR_PLANE_M, NEAR_PLANE_M, frustum_planes, projection_matrix, view_matrix

CAMERA = Camera((0.0, 0.0, 1000.0), (0.0, 0.0, 0.0), 60.0)


def splat_scene(*particles) -> Scene:
    return Scene(camera=CAMERA, clouds=(Cloud("c", np.array(particles, dtype=np.float64)),))


def test_analytic_overdraw_of_one_disc_is_its_share_of_the_screen():
    view, projection = view_matrix(CAMERA), projection_matrix(60.0, 4 / 3)
    half_height = 1000.0 * np.tan(np.radians(30.0))  # world metres at the splat's depth
    screen_area = (2 * half_height) * (2 * half_height * 4 / 3)
    estimate = analytic_overdraw(np.zeros((1, 3)), np.array([100.0]), view, projection, NEAR_PLANE_M)
    assert estimate == pytest.approx(np.pi * 100.0**2 / screen_area)


def test_splats_behind_the_near_plane_are_not_estimated():
    view, projection = view_matrix(CAMERA), projection_matrix(60.0, 1.0)
    behind = np.array([[0.0, 0.0, 1500.0]])
    assert analytic_overdraw(behind, np.array([10.0]), view, projection, NEAR_PLANE_M) == 0.0


def test_a_splat_of_no_radius_adds_nothing_to_the_estimate():
    view, projection = view_matrix(CAMERA), projection_matrix(60.0, 4 / 3)
    one = analytic_overdraw(np.zeros((1, 3)), np.array([100.0]), view, projection, NEAR_PLANE_M)
    both = analytic_overdraw(np.zeros((2, 3)), np.array([100.0, 0.0]), view, projection, NEAR_PLANE_M)
    assert both == one  # not NaN: the share on screen of a point is not asked


def test_statistics_of_known_counts():
    counts = np.array([[0.0, 2.0], [4.0, 0.0]], dtype=np.float32)
    assert overdraw_statistics(counts, 2.0) == Overdraw(mean=1.5, mean_covered=3.0, max=4.0, analytic=2.0)


def test_counted_fragments_match_the_disc_and_stack(renderer):
    one = splat_scene([0.0, 0.0, 0.0, 150.0])
    renderer.render(one, time_of_day=12.0, settings=FULL_3D)
    counts, stats = renderer.measure_overdraw()
    assert stats.max == 1.0
    # pixel coverage of a disc ~1,700 pixels large agrees with its area within rasterisation error
    assert stats.mean == pytest.approx(stats.analytic, rel=0.03)

    renderer.render(splat_scene([0.0, 0.0, 0.0, 150.0], [0.0, 0.0, 0.0, 150.0]), time_of_day=12.0, settings=FULL_3D)
    counts_two, _ = renderer.measure_overdraw()
    assert np.array_equal(counts_two, 2 * counts)


def test_analytic_overdraw_counts_only_the_part_on_screen():
    view, projection = view_matrix(CAMERA), projection_matrix(60.0, 1.0)
    edge = 1000.0 * np.tan(np.radians(30.0))  # the right screen edge at the splat's depth
    centred = analytic_overdraw(np.zeros((1, 3)), np.array([50.0]), view, projection, NEAR_PLANE_M)
    on_edge = analytic_overdraw(np.array([[edge, 0.0, 0.0]]), np.array([50.0]), view, projection, NEAR_PLANE_M)
    assert on_edge == pytest.approx(centred / 2)


def test_splats_in_view_keeps_what_the_frustum_keeps_and_estimates_those():
    """The planner's one-transform cull and estimate against the world-space cull and `analytic_overdraw`:
    splats round the eye, behind it, astride the near plane, past the far plane and along every side."""
    rng = np.random.default_rng(3)
    camera = Camera((100.0, 50.0, 900.0), (0.0, 30.0, 0.0), 50.0)
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, 16 / 9)
    eye, forward = np.array(camera.position), np.array(camera.look_at) - np.array(camera.position)
    forward /= np.linalg.norm(forward)
    centres = np.concatenate(
        [
            eye + rng.normal(scale=300.0, size=(4000, 3)),
            eye + forward * rng.uniform(FAR_PLANE_M - 50.0, FAR_PLANE_M + 50.0, size=(200, 1)),
            eye + forward * rng.uniform(-1.0, 2.0 * NEAR_PLANE_M, size=(200, 1)),
        ]
    )
    radii = rng.uniform(0.0, 60.0, size=len(centres))
    kept = splats_in_frustum(frustum_planes(projection @ view), centres, radii)
    assert 0 < np.count_nonzero(kept) < len(radii)
    count, overdraw = splats_in_view(centres, radii, view, projection)
    assert count == np.count_nonzero(kept)
    assert overdraw == pytest.approx(analytic_overdraw(centres[kept], radii[kept], view, projection, NEAR_PLANE_M))


def test_splats_in_view_per_set_is_each_sets_own_in_one_pass():
    """The planner's near units counted together: each set's splats kept and overdraw as `splats_in_view` gives them
    for that set alone, an empty set (first, between, last) none, and a set wholly out of view none."""
    rng = np.random.default_rng(5)
    camera = Camera((100.0, 50.0, 900.0), (0.0, 30.0, 0.0), 50.0)
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, 16 / 9)
    eye = np.array(camera.position)
    behind = eye + (eye - np.array(camera.look_at)) / np.linalg.norm(eye - np.array(camera.look_at)) * 500.0
    sets = [
        (np.zeros((0, 3)), np.zeros(0)),
        (eye + rng.normal(scale=300.0, size=(900, 3)), rng.uniform(0.0, 60.0, 900)),
        (np.zeros((0, 3)), np.zeros(0)),
        (behind + rng.normal(scale=20.0, size=(50, 3)), rng.uniform(1.0, 5.0, 50)),
        (np.array(camera.look_at) + rng.normal(scale=200.0, size=(400, 3)), rng.uniform(10.0, 90.0, 400)),
        (np.zeros((0, 3)), np.zeros(0)),
    ]
    kept, overdraws = splats_in_view_per_set(
        np.concatenate([c for c, _ in sets]),
        np.concatenate([r for _, r in sets]),
        [len(r) for _, r in sets],
        view,
        projection,
    )
    alone = [splats_in_view(c, r, view, projection) if len(r) else (0, 0.0) for c, r in sets]
    assert kept.tolist() == [count for count, _ in alone]
    np.testing.assert_allclose(overdraws, [overdraw for _, overdraw in alone], rtol=1e-12, atol=0.0)
    assert kept[1] > 0 and kept[4] > 0 and overdraws[1] > 0.0 and kept[3] == 0 and overdraws[3] == 0.0
