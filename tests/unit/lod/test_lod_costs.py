"""The cost model without GL: predicted work, the fit to measured times, and the frame budget in the plan."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.lod.costs import (
    FRAMES_TO_REMEMBER,
    LLVMPIPE_COSTS,
    MEMORY_VARIABLE,
    CostEstimator,
    CostModel,
    Work,
    inverse_square_depth,
    regeneration_fragments,
    remember_fit,
    remembered_prior,
    splat_fragments,
)
from cloudcore.lod.plan import SWITCH_MARGIN, LodState
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.runtime import disk_cache
from cloudcore.scenes.files import load_scene
from tests.unit.lod.test_frameplan import FILL_BOUND, FINEST, NO_RING, RADIUS, camera_at, plan


def test_splat_fragments_are_the_discs_areas_and_never_more_than_the_screen_each():
    # 100 splats of 2 m in a point-like unit at 1000 m, focal 500 px: discs of 1 px radius
    assert splat_fragments(100 * 2.0**2, 0.0, 1000.0, 500.0, 100, 640 * 480) == pytest.approx(100 * math.pi)
    assert splat_fragments(100 * 2.0**2, 10.0, 0.0, 500.0, 100, 640 * 480) == 100 * 640 * 480
    assert np.isfinite(splat_fragments(1e30, 1.0, 1e-300, 1e4, 1, 1.0))


@pytest.mark.parametrize("distance", [1.05, 1.5, 3.0, 4.9, 5.1, 20.0, 1e6])
def test_the_inverse_square_depth_of_a_ball_against_sampling_it(distance):
    """The closed form (and its far series) against the mean of 1/z^2 over points of a unit ball."""
    rng = np.random.default_rng(5)
    points = rng.uniform(-1.0, 1.0, size=(400000, 3))
    points = points[np.linalg.norm(points, axis=1) <= 1.0]
    sampled = np.mean(1.0 / (distance + points[:, 2]) ** 2)
    assert inverse_square_depth(1.0, distance) == pytest.approx(sampled, rel=0.02)
    assert inverse_square_depth(1.0, 1e6) * 1e12 == pytest.approx(1.0)
    assert inverse_square_depth(1.0, 1.05) * 1.05**2 == pytest.approx(3.14, rel=0.01)  # the near side looms


def test_remaking_an_impostor_costs_its_particles_and_a_fill_that_grows_with_the_texture():
    small, large = regeneration_fragments(1000, 1000 * 25.0, 100.0, 1000.0, 200.0, np.array([64, 256]))
    assert large == pytest.approx(16 * small)
    # one pixel-sized texture: each splat fills it at most
    assert regeneration_fragments(1000, 1000 * 25.0, 100.0, 101.0, 1e-300, 1) == pytest.approx(1000.0)


def test_the_estimator_recovers_the_coefficients_that_made_the_times():
    """Frames of varied work timed by a hidden model: the fit converges to it from the llvmpipe prior."""
    truth = CostModel(
        particles=3e-4,
        fragments=1e-5,
        texture_fragments=2e-5,
        quad_pixels=5e-6,
        quads=0.02,
        regenerations=2.0,
        batches=0.05,
    )
    rng = np.random.default_rng(3)
    estimator = CostEstimator()
    for _ in range(200):
        updates = Work(
            particles=rng.uniform(0, 2e4), texture_fragments=rng.uniform(0, 2e6), regenerations=rng.integers(0, 16)
        )
        clouds = Work(
            particles=rng.uniform(0, 8e4),
            fragments=rng.uniform(0, 2e7),
            quad_pixels=rng.uniform(0, 6e5),
            quads=rng.integers(0, 200),
            batches=rng.integers(1, 4),
        )
        estimator = estimator.observe([(updates, truth.ms(updates)), (clouds, truth.ms(clouds))])
    fitted = estimator.model()
    # within auto mode's switch margin (25%): the prior still pulls on the small terms (a quad pixel, a
    # regeneration's fixed cost: 24% and 16% here, with seven terms fitted from two passes a frame)
    recovered = ("particles", "fragments", "texture_fragments", "quad_pixels", "quads", "regenerations")
    np.testing.assert_allclose(
        [getattr(fitted, n) for n in recovered], [getattr(truth, n) for n in recovered], rtol=SWITCH_MARGIN
    )
    # a splat draw's fixed cost adds under 0.15 ms to any of these frames: far too little evidence to move a
    # strong prior (by design: frame-time noise must not either); it only leans toward the truth
    assert truth.batches < fitted.batches < LLVMPIPE_COSTS.batches
    assert CostEstimator().model() == LLVMPIPE_COSTS  # before any frame, the prior


def test_the_estimator_learns_a_reduced_pass_s_fixed_cost_from_the_frames_drawn_with_one():
    """Frames now at the screen's resolution, now through a reduced pass whose fixed cost (the wait for the world's
    depth) is a third of the prior's: the fit finds it, and leaves the other coefficients where they were."""
    truth = dataclasses.replace(LLVMPIPE_COSTS, upsampled_pixels=LLVMPIPE_COSTS.upsampled_pixels / 3.0)
    rng = np.random.default_rng(5)
    estimator = CostEstimator()
    for frame in range(120):
        reduced = frame % 3 == 0
        clouds = Work(
            particles=rng.uniform(1e3, 3e4),
            fragments=rng.uniform(1e5, 4e6) / (16.0 if reduced else 1.0),
            quad_pixels=rng.uniform(0, 3e5) / (16.0 if reduced else 1.0),
            quads=rng.integers(1, 100),
            batches=rng.integers(1, 4),
            upsampled_pixels=3e5 if reduced else 0.0,
        )
        estimator = estimator.observe([(clouds, truth.ms(clouds))])
    fitted = estimator.model()
    # from three times the truth to within 30% of it (the prior still pulls, and its composite's pixels share the
    # frames it is drawn in)
    assert fitted.upsampled_pixels == pytest.approx(truth.upsampled_pixels, rel=0.3)
    for name in ("particles", "fragments", "quad_pixels"):
        assert getattr(fitted, name) == pytest.approx(getattr(truth, name), rel=SWITCH_MARGIN), name


def test_the_estimator_ignores_broken_timings_and_keeps_coefficients_positive():
    estimator = CostEstimator().observe(
        [(Work(particles=1e4), math.nan), (Work(particles=1e4), -5.0), (Work(particles=1e4), math.inf)]
    )
    assert estimator.model() == LLVMPIPE_COSTS
    for _ in range(50):  # times far below what any work could cost: clipped, not negative or zero
        estimator = estimator.observe([(Work(particles=1e5, fragments=1e7), 1e-9)])
    assert np.all(estimator.model().vector() > 0.0)


RING_OF_CLOUDS = tuple((600.0 * math.sin(a), 0.0, -600.0 * math.cos(a)) for a in np.radians([-20, -10, 0, 10, 20]))


def test_a_frame_budget_postpones_regenerations_and_reports_the_error_it_accepted():
    impostors = dataclasses.replace(NO_RING, mode="impostor")
    start = camera_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0))

    def five_clouds(camera, settings, state=None, finest_radii=FINEST * 5):
        return plan(
            camera,
            settings,
            state=state,
            centres=RING_OF_CLOUDS,
            radii=(RADIUS,) * 5,
            finest_radii=finest_radii,
            costs=FILL_BOUND,
        )

    first = five_clouds(start, impostors)
    moved = camera_at((40.0, 0.0, 0.0), (40.0, 0.0, -1.0))
    unlimited = five_clouds(moved, impostors, first.state)
    assert unlimited.stats().impostors_regenerated == 5 and unlimited.accepted_error <= 1.0
    # room for the quads and two regenerations: the two farthest past the tolerance are served
    one = FILL_BOUND.ms(unlimited.update_work) / 5
    budget = dataclasses.replace(impostors, frame_budget_ms=FILL_BOUND.ms(unlimited.cloud_work) + 2.5 * one)
    tight = five_clouds(moved, budget, first.state)
    stats = tight.stats()
    assert (stats.impostors_regenerated, stats.regenerations_postponed) == (2, 3)
    assert tight.predicted_ms <= budget.frame_budget_ms < unlimited.predicted_ms
    assert tight.accepted_error > 1.0 and stats.accepted_error_tolerances == tight.accepted_error
    # a budget below the quads' own cost still serves the most urgent one a frame: the picture converges
    starved = five_clouds(moved, dataclasses.replace(impostors, frame_budget_ms=1e-6), first.state)
    assert (starved.stats().impostors_regenerated, starved.stats().regenerations_postponed) == (1, 4)
    # new impostors are made whatever the budget: there is nothing else to show
    fresh = five_clouds(start, dataclasses.replace(impostors, frame_budget_ms=1e-6), finest_radii=None)
    assert fresh.stats().impostors_regenerated == 5


def test_the_plan_predicts_the_work_it_schedules():
    p = plan(camera_at((0.0, 0.0, 1000.0)), dataclasses.replace(NO_RING, mode="impostor"), costs=FILL_BOUND)
    assert p.priced and p.cloud_work.quads == 1 and p.update_work.particles == 1000
    assert p.predicted_ms == pytest.approx(FILL_BOUND.ms(p.update_work + p.cloud_work))
    assert isinstance(p.state, LodState) and p.state.eye == (0.0, 0.0, 1000.0)


def test_full_3d_prices_nothing_and_its_frames_fit_no_costs():
    """Full 3D draws every unit in view whatever it costs: its plan counts no work, and its measured passes
    leave the cost fit as it was (they still time the way auto mode drew, when auto planned as full 3D)."""
    p = plan(camera_at((0.0, 0.0, 1000.0)), dataclasses.replace(NO_RING, mode="full"), costs=FILL_BOUND)
    assert not p.priced and not p.stats().priced
    assert (p.update_work, p.cloud_work, p.predicted_ms) == (Work(), Work(), 0.0)
    assert [c.kind for c in p.clouds] == ["full"] and p.draw_order == (0,)
    measured = p.state.measured([(p.update_work, 2.0), (p.cloud_work, 30.0)], fit=p.priced)
    assert measured.costs is p.state.costs
    assert p.state.measured([(Work(particles=1000.0), 30.0)]).costs.frames == p.state.costs.frames + 1


def test_a_cost_model_prices_each_field_of_work_by_its_own_coefficient():
    """`CostModel.ms` pairs coefficients and counts by name: the two classes must have the same fields."""
    assert [f.name for f in dataclasses.fields(CostModel)] == [f.name for f in dataclasses.fields(Work)]
    names = [f.name for f in dataclasses.fields(Work)]
    for index, name in enumerate(names):
        model = CostModel(**{n: 10.0 ** (k + 1) for k, n in enumerate(names)})
        assert model.ms(Work(**{name: 2.0})) == 2.0 * 10.0 ** (index + 1)
    assert (Work(particles=1.0, quads=2.0) + Work(quads=3.0)).scaled(2.0) == Work(particles=2.0, quads=10.0)
    assert Work(**{n: float(k) for k, n in enumerate(names)}).values() == tuple(map(float, range(len(names))))


MACHINE = {"gl": "llvmpipe (test)", "processor": "x86_64", "cores": 2, "format": 1}


def fitted_estimator(frames: int) -> CostEstimator:
    """An estimator that has seen `frames` frames of particles costing three times the prior."""
    estimator = CostEstimator()
    for _ in range(frames):
        work = Work(particles=5e4, fragments=1e6)
        estimator = estimator.observe([(work, 3.0 * LLVMPIPE_COSTS.ms(work))])
    return estimator


def test_a_fitted_cost_model_is_remembered_for_the_next_run_on_the_same_machine(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv(MEMORY_VARIABLE, "on")
    assert remembered_prior(MACHINE) is None
    assert not remember_fit(MACHINE, fitted_estimator(FRAMES_TO_REMEMBER - 1))  # too few frames to go by
    assert remembered_prior(MACHINE) is None
    estimator = fitted_estimator(FRAMES_TO_REMEMBER)
    assert remember_fit(MACHINE, estimator)
    assert remembered_prior(MACHINE) == estimator.model() != LLVMPIPE_COSTS
    # another GL, or the memory turned off, starts from the prior
    assert remembered_prior({**MACHINE, "gl": "NVIDIA H200"}) is None
    monkeypatch.setenv(MEMORY_VARIABLE, "off")
    assert remembered_prior(MACHINE) is None and not remember_fit(MACHINE, estimator)


def test_a_remembered_cost_model_that_is_not_a_model_is_not_used(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv(MEMORY_VARIABLE, "on")
    for coefficients in ([1.0, 2.0], [math.nan] * 7, [0.0] * 7, [-1.0] * 7):
        disk_cache.store("cost-model", MACHINE, {"coefficients": np.array(coefficients)})
        assert remembered_prior(MACHINE) is None, coefficients


@pytest.mark.gl
def test_a_renderer_that_remembers_starts_from_the_fit_the_last_one_left(tmp_path, monkeypatch):
    from cloudcore.gl import FrameRenderer

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv(MEMORY_VARIABLE, "on")
    scene = load_scene(DEFAULT_SCENE)
    with FrameRenderer(160, 120, remember_costs=True) as first:
        for _ in range(FRAMES_TO_REMEMBER):
            first.render(scene, read_back=False)
        fitted = first.lod_state.costs.model()
    assert fitted != LLVMPIPE_COSTS
    with FrameRenderer(160, 120, remember_costs=True) as second:
        assert second.lod_state.costs.prior == fitted and second.lod_state.costs.model() == fitted
    with FrameRenderer(160, 120) as forgetful:  # the tests' and benchmarks' renderers start alike
        assert forgetful.lod_state.costs.model() == LLVMPIPE_COSTS
