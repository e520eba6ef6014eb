"""Clouds forming from the core and dissipating from the edges (Wang 2004 section 4): the factor,
its scene-file field and its effect on what particles send to the eye."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.artist.formation import core_distances, formation_state, opacity_factor, progress
from cloudcore.model.cloud_records import Formation
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Cloud, Light, Shading
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.scenes.files import load_scene, save_scene

START, DURATION = 10.0, 30.0
TIMES = np.linspace(START - 5.0, START + DURATION + 5.0, 161)


def ragged_cloud(scale=1.0, count=300, seed=3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(count, 3)) * [400.0, 150.0, 300.0] + [50.0, 900.0, -20.0]
    return np.column_stack([centres, rng.uniform(20.0, 60.0, count)]) * scale


def factors_over_time(kind: str, distances: np.ndarray) -> np.ndarray:
    """(times, particles) opacity factors, particles in order of increasing distance from the core."""
    formation = Formation(kind, START, DURATION)
    return np.array([opacity_factor(formation, np.sort(distances), t) for t in TIMES])


def test_forming_alpha_falls_from_core_to_edge_and_rises_with_time_until_fully_formed():
    factors = factors_over_time("form", core_distances(ragged_cloud()[:, :3]))
    assert np.all(np.diff(factors, axis=1) <= 0)  # nearer the core: at least as opaque
    assert np.all(np.diff(factors, axis=0) >= 0)  # no particle ever fades while forming
    assert np.all(factors[TIMES <= START] == 0.0)  # nothing before it starts
    assert np.all(factors[TIMES >= START + DURATION] == 1.0)  # exactly opaque once formed
    # the core shows first: part way in, the core is visible while the edge is not yet
    early = factors[np.searchsorted(TIMES, START + 0.25 * DURATION)]
    assert early[0] > 0.0 and early[-1] == 0.0


def test_dissipating_edge_goes_first_and_the_cloud_is_fully_gone_at_the_end():
    factors = factors_over_time("dissipate", core_distances(ragged_cloud()[:, :3]))
    assert np.all(np.diff(factors, axis=1) <= 0)  # the edge is always the more transparent
    assert np.all(np.diff(factors, axis=0) <= 0)  # no particle ever returns while dissipating
    assert np.all(factors[TIMES <= START] == 1.0)
    assert np.all(factors[TIMES >= START + DURATION] == 0.0)  # fully gone
    early = factors[np.searchsorted(TIMES, START + 0.25 * DURATION)]
    assert early[0] == 1.0 and early[-1] < 1.0
    late = factors[np.searchsorted(TIMES, START + 0.75 * DURATION)]
    assert late[0] > 0.0 and late[-1] == 0.0


def test_dissipation_is_formation_played_backwards():
    distances = np.linspace(0.0, 1.0, 11)
    forming, dissipating = Formation("form", 0.0, 8.0), Formation("dissipate", 0.0, 8.0)
    for t in np.linspace(0.0, 8.0, 17):
        np.testing.assert_allclose(
            opacity_factor(dissipating, distances, t), opacity_factor(forming, distances, 8.0 - t), atol=1e-15
        )


def test_zero_duration_is_instant():
    distances = np.linspace(0.0, 1.0, 5)
    form, dissipate = Formation("form", 2.0, 0.0), Formation("dissipate", 2.0, 0.0)
    assert np.all(opacity_factor(form, distances, 1.999) == 0.0)
    assert np.all(opacity_factor(form, distances, 2.0) == 1.0)
    assert np.all(opacity_factor(dissipate, distances, 1.999) == 1.0)
    assert np.all(opacity_factor(dissipate, distances, 2.0) == 0.0)


def test_progress_is_clamped_and_linear():
    f = Formation("form", 10.0, 4.0)
    assert [progress(f, t) for t in (0.0, 10.0, 11.0, 12.0, 14.0, 1e300)] == [0.0, 0.0, 0.25, 0.5, 1.0, 1.0]


@pytest.mark.parametrize(
    "particles, expected",
    [
        (np.zeros((0, 4)), []),
        (np.array([[5.0, 6.0, 7.0, 1.0]]), [0.0]),
        (np.tile([1.0, 2.0, 3.0, 4.0], (5, 1)), [0.0] * 5),
        (np.array([[-1.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0], [3.0, 0.0, 0.0, 1.0]]), [1.0, 0.5, 1.0]),
    ],
)
def test_core_distances_of_degenerate_clouds(particles, expected):
    np.testing.assert_allclose(core_distances(particles[:, :3]), expected, atol=1e-15)
    for kind in ("form", "dissipate"):
        factor = opacity_factor(Formation(kind, 0.0, 1.0), core_distances(particles[:, :3]), 0.5)
        assert factor.shape == (len(particles),) and np.all(np.isfinite(factor))


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1.0, 1e3, 1e6, 1e300])
def test_core_distances_do_not_depend_on_scale_and_stay_finite(scale):
    unit = core_distances(ragged_cloud()[:, :3])
    scaled = core_distances(ragged_cloud(scale)[:, :3])
    assert np.all(np.isfinite(scaled)) and scaled.min() >= 0.0 and scaled.max() == 1.0
    np.testing.assert_allclose(scaled, unit, rtol=1e-12, atol=1e-12)


def test_core_distances_at_the_ends_of_the_float_range_are_finite():
    centres = np.array([[-1.7e308, 0.0, 0.0], [1.7e308, 1.7e308, -1.7e308], [1e-300, 0.0, 0.0]])
    distances = core_distances(centres)
    assert np.all(np.isfinite(distances)) and distances.max() == 1.0


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Formation("grow", 0.0, 1.0), "grow"),
        (lambda: Formation("form", 0.0, -1.0), "duration_s"),
        (lambda: Formation("form", 0.0, math.nan), "duration_s"),
        (lambda: Formation("form", math.inf, 1.0), "start_s"),
        (lambda: Formation("form", math.nan, 1.0), "start_s"),
        (lambda: progress(Formation("form", 0.0, 1.0), math.nan), "time_s"),
        (lambda: opacity_factor(Formation("form", 0.0, 1.0), np.array([0.5]), math.inf), "time_s"),
        (lambda: opacity_factor(Formation("form", 0.0, 1.0), np.array([math.nan]), 0.5), "NaN"),
    ],
)
def test_out_of_domain_input_is_refused_with_a_message(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_state_is_constant_outside_the_animation_and_changes_inside():
    f = Formation("dissipate", START, DURATION)
    before = {formation_state(f, t) for t in (-1e9, 0.0, START)}
    after = {formation_state(f, t) for t in (START + DURATION, 1e3, 1e12)}
    assert len(before) == 1 and len(after) == 1 and before != after
    assert formation_state(f, START + 1.0) != formation_state(f, START + 2.0)
    assert formation_state(None, 5.0) == formation_state(None, 6.0)
    hash(formation_state(f, START + 1.0))


# ---------------------------------------------------------------- scene files


def test_formation_survives_a_save_and_load(tmp_path, small_scene):
    forming = Formation("form", 12.5, 40.0)
    clouds = (
        dataclasses.replace(small_scene.clouds[0], formation=forming),
        dataclasses.replace(small_scene.clouds[1], formation=Formation("dissipate", 0.0, 0.0)),
    )
    scene = dataclasses.replace(small_scene, clouds=clouds)
    saved = save_scene(scene, tmp_path / "s.toml")
    loaded = load_scene(tmp_path / "s.toml")
    assert loaded == saved
    assert loaded.clouds[0].formation == forming
    assert loaded.clouds[1].formation == Formation("dissipate", 0.0, 0.0)  # kept in the .npy cloud too


def test_formation_is_optional_and_start_defaults_to_zero(tmp_path):
    (tmp_path / "s.toml").write_text(SCENE.format(formation='{ kind = "form", duration_s = 3 }'))
    assert load_scene(tmp_path / "s.toml").clouds[0].formation == Formation("form", 0.0, 3.0)
    (tmp_path / "s.toml").write_text(SCENE.replace("formation = {formation}\n", ""))
    assert load_scene(tmp_path / "s.toml").clouds[0].formation is None


SCENE = """
[[clouds]]
name = "a"
particles = [[0.0, 800.0, 0.0, 20.0]]
formation = {formation}
"""


@pytest.mark.parametrize(
    "formation, field, problem",
    [
        ('{ kind = "grow", duration_s = 3 }', "clouds[0].formation.kind", "form, dissipate"),
        ("{ duration_s = 3 }", "clouds[0].formation.kind", "missing"),
        ('{ kind = "form" }', "clouds[0].formation.duration_s", "missing"),
        ('{ kind = "form", duration_s = -1 }', "clouds[0].formation.duration_s", "within"),
        ('{ kind = "form", duration_s = nan }', "clouds[0].formation.duration_s", "finite"),
        ('{ kind = "form", duration_s = 3, start_s = inf }', "clouds[0].formation.start_s", "finite"),
        ('{ kind = "form", duration_s = "3" }', "clouds[0].formation.duration_s", "expected a number"),
        ('{ kind = "form", duration_s = 3, speed = 2 }', "clouds[0].formation.speed", "unknown key"),
        ('"form"', "clouds[0].formation", "expected a table"),
    ],
)
def test_bad_formation_names_file_field_and_problem(tmp_path, formation, field, problem):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE.format(formation=formation))
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert (caught.value.source, caught.value.field) == (str(path), field)
    assert problem in caught.value.problem


# ---------------------------------------------------------------- what the eye sees


def shading_of(clouds) -> ParticleBuffer:
    return ParticleBuffer(clouds, Shading(), [Light((0.0, 1.0, 0.0))], (0.1, 0.1, 0.1))


EYE = np.array([0.0, 900.0, 3000.0])


def test_seen_from_scales_colour_and_opacity_of_forming_clouds_only():
    steady = Cloud("steady", ragged_cloud(seed=1))
    forming = Cloud(
        "forming", ragged_cloud(seed=2) + [2000.0, 0.0, 0.0, 0.0], formation=Formation("form", START, DURATION)
    )
    particles = shading_of((steady, forming))
    indices = np.arange(particles.cloud_starts[-1])[::-1]
    colour, alpha = particles.seen_from(EYE, indices)
    t = START + 0.4 * DURATION
    colour_t, alpha_t = particles.seen_from(EYE, indices, time_s=t)
    factor = np.concatenate(
        [np.ones(len(steady.particles)), opacity_factor(forming.formation, core_distances(forming.centres), t)]
    )[indices]
    np.testing.assert_array_equal(alpha_t, alpha * factor)
    np.testing.assert_array_equal(colour_t, colour * factor[:, None])
    assert np.any((0.0 < factor) & (factor < 1.0))  # the instant shows a partly formed cloud
    _, alpha_done = particles.seen_from(EYE, indices, time_s=START + DURATION)
    np.testing.assert_array_equal(alpha_done, alpha)
    colour_before, alpha_before = particles.seen_from(EYE, indices, time_s=START - 1.0)
    in_forming = indices >= particles.cloud_starts[1]
    assert np.all(alpha_before[in_forming] == 0.0) and np.all(colour_before[in_forming] == 0.0)
    np.testing.assert_array_equal(alpha_before[~in_forming], alpha[~in_forming])


def test_without_formations_time_changes_nothing():
    particles = shading_of((Cloud("a", ragged_cloud()),))
    indices = np.arange(particles.cloud_starts[-1])
    without, with_time = particles.seen_from(EYE, indices), particles.seen_from(EYE, indices, time_s=123.0)
    np.testing.assert_array_equal(without[0], with_time[0])
    np.testing.assert_array_equal(without[1], with_time[1])


def test_a_dissipated_cloud_sends_nothing():
    cloud = Cloud("gone", ragged_cloud(), formation=Formation("dissipate", 0.0, 5.0))
    particles = shading_of((cloud, Cloud("empty")))
    colour, alpha = particles.seen_from(EYE, np.arange(len(cloud.particles)), time_s=5.0)
    assert np.all(colour == 0.0) and np.all(alpha == 0.0)
