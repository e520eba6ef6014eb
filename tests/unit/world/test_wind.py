"""The wind (`cloudcore.world.wind`, `[wind]`): drift by altitude band with gusts, turbulence that keeps clouds whole,
impostors that know their clouds moved, and the keys refused in one line."""

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest

from cloudcore.field.state import update_field
from cloudcore.light.cloud_shadows import light_space
from cloudcore.lod.costs import CostModel
from cloudcore.lod.impostors import ImpostorRecord, parallax_errors_deg
from cloudcore.lod.plan import plan_frame
from cloudcore.lod.plan.pricing import LONGEST_LIFETIME_FRAMES, held_impostor_errors, pricing_of, seen_from
from cloudcore.lod.plan.state import LodState
from cloudcore.lod.units import LodUnits
from cloudcore.model.errors import FieldError
from cloudcore.model.scene import Camera, CloudField, Scene, Wind, splats_bounding_sphere
from cloudcore.model.settings import RenderSettings
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import TABLE_KEYS, load_scene, save_scene, scene_from_dict
from cloudcore.world.wind import (
    AirMotion,
    CloudMotion,
    carried_seconds,
    drift,
    field_drift,
    light_time,
    shape_change_bound_m,
    turbulent_offsets,
    velocity_at,
)
from tests.conftest import assert_file_refused_in_one_line

TEN_MINUTES = np.arange(0.0, 601.0, 1.0)


def test_directions_are_where_the_wind_blows_from_clockwise_from_north():
    speeds = velocity_at(Wind(bands=((0.0, 10.0, 270.0),)), [0.0])[0]
    np.testing.assert_allclose(speeds, [10.0, 0.0, 0.0], atol=1e-12)  # a westerly carries clouds east (+x)
    for bearing, toward in ((0.0, [0, 0, 1]), (90.0, [-1, 0, 0]), (180.0, [0, 0, -1]), (360.0, [0, 0, 1])):
        np.testing.assert_allclose(
            velocity_at(Wind(bands=((0.0, 4.0, bearing),)), [500.0])[0], 4.0 * np.array(toward), atol=1e-12
        )


def test_bands_interpolate_as_vectors_and_the_nearest_holds_beyond_them():
    wind = Wind(bands=((1000.0, 10.0, 270.0), (3000.0, 10.0, 90.0)))
    low, middle, high = velocity_at(wind, [0.0, 2000.0, 9000.0])
    np.testing.assert_allclose(low, [10.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(middle, [0.0, 0.0, 0.0], atol=1e-12)  # opposed bands: a calm between, not a veer
    np.testing.assert_allclose(high, [-10.0, 0.0, 0.0], atol=1e-12)


def test_the_drift_is_the_integral_of_the_gusty_wind_with_no_jump_and_no_step_back():
    wind = Wind(bands=((0.0, 12.0, 200.0),), gust_amplitude=1.0, gust_period_s=30.0)
    times = np.linspace(0.0, 300.0, 30001)
    speeds = 1.0 + np.sin(2.0 * np.pi * times / 30.0)
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (speeds[1:] + speeds[:-1]) * np.diff(times))])
    closed = np.array([carried_seconds(wind, t) for t in times])
    np.testing.assert_allclose(closed, integral, atol=1e-5)  # the trapezoids' error
    assert np.all(np.diff(closed) >= 0.0)  # gusts of amplitude 1 stop the cloud, never turn it back
    assert np.max(np.abs(np.diff(closed))) <= 2.0 * 0.01 + 1e-12  # continuous: at most the fastest speed a step
    np.testing.assert_array_equal(drift(wind, [100.0], 0.0), np.zeros((1, 3)))


def clouds_of_the_default_scene():
    return load_scene(DEFAULT_SCENE).clouds


def test_a_cloud_s_centre_moves_by_the_wind_s_displacement():
    clouds = clouds_of_the_default_scene()
    wind = Wind(bands=((0.0, 5.0, 270.0), (2000.0, 25.0, 300.0)), gust_amplitude=0.4, gust_period_s=50.0)
    air = AirMotion(wind, clouds)
    for time_s in (0.0, 37.5, 600.0):
        # the clouds as their light was made (bands apart: every `relight_period_s`), carried on to `time_s`
        lit_at = light_time(wind, time_s)
        moved = np.concatenate([c.centres for c in air.lit_clouds(lit_at)]) + air.carry(time_s, lit_at)
        for index in (0, 7, len(clouds) - 1):
            cloud = clouds[index]
            start = int(np.sum(air.counts[:index]))
            centre, _ = splats_bounding_sphere(moved[start : start + len(cloud.radii)], cloud.radii)
            expected = drift(wind, [cloud.bounding_sphere()[0][1]], time_s)[0]
            np.testing.assert_allclose(centre - cloud.bounding_sphere()[0], expected, atol=1e-6)


def test_a_pure_drift_keeps_the_clouds_and_their_light_at_rest_and_turbulence_relights_at_its_period():
    clouds = clouds_of_the_default_scene()
    drifting = AirMotion(Wind(bands=((0.0, 20.0, 10.0),)), clouds)
    assert light_time(drifting.wind, 250.0) == 0.0 and drifting.lit_clouds(0.0) is clouds
    churning = AirMotion(Wind(turbulence_m=30.0, relight_period_s=10.0), clouds)
    assert light_time(churning.wind, 5.0) == 0.0  # the first period's light is the clouds' at rest
    assert [light_time(churning.wind, t) for t in (23.0, 29.9, 30.0)] == [20.0, 20.0, 30.0]
    lit = churning.lit_clouds(20.0)
    assert lit is churning.lit_clouds(20.0) and lit is not churning.lit_clouds(30.0)
    assert churning.lit_clouds(20.0) is lit  # the last two kept: the editor draws one while the next is lit
    # the lit clouds are where the wind had them at 20 s; the carry takes them on to 23 s, or from an older light
    for lit_at in (20.0, 10.0):
        np.testing.assert_allclose(
            np.concatenate([c.centres for c in churning.lit_clouds(lit_at)]) + churning.carry(23.0, lit_at),
            churning.rest + churning.offsets(23.0),
        )
    # bands that carry clouds apart change their light on one another: relit too
    assert light_time(Wind(bands=((0.0, 5.0, 270.0), (3000.0, 15.0, 270.0))), 83.0) == 60.0


def test_the_turbulent_field_is_divergence_free_and_bounded():
    wind = Wind(turbulence_m=80.0, turbulence_scale_m=300.0, turbulence_period_s=40.0)
    points = np.random.default_rng(57).normal(size=(200, 3)) * 700.0
    step = 1e-2
    divergence = sum(
        (
            turbulent_offsets(wind, points + step * axis, 13.0)[:, i]
            - turbulent_offsets(wind, points - step * axis, 13.0)[:, i]
        )
        / (2.0 * step)
        for i, axis in enumerate(np.eye(3))
    )
    # each term's derivative is up to 80 * 2 pi / 300 = 1.7; the sum cancels to rounding
    assert np.max(np.abs(divergence)) < 1e-6
    lengths = np.linalg.norm(np.stack([turbulent_offsets(wind, points, t) for t in TEN_MINUTES]), axis=-1)
    assert lengths.max() <= 80.0 and lengths.max() > 40.0  # bounded by the amplitude, and near it somewhere


def test_over_ten_minutes_turbulence_keeps_every_cloud_s_particles_and_extent_within_the_amplitude():
    clouds = clouds_of_the_default_scene()
    amplitude = 40.0
    # no drift: the cloud's own change alone
    air = AirMotion(Wind(bands=((0.0, 0.0, 0.0),), turbulence_m=amplitude), clouds)
    starts = np.concatenate([[0], np.cumsum(air.counts)])
    rest_radii = np.array([c.bounding_sphere()[1] for c in clouds])
    for time_s in TEN_MINUTES[::10]:
        offsets = air.offsets(time_s)  # from each particle's place at rest
        assert offsets.shape == air.rest.shape  # every particle kept
        assert np.linalg.norm(offsets, axis=1).max() <= amplitude  # each at most the amplitude from its place
        moved = air.rest + offsets
        for index, cloud in enumerate(clouds):
            centre, radius = splats_bounding_sphere(moved[starts[index] : starts[index + 1]], cloud.radii)
            # the sphere about the cloud's centre at rest that holds it grows by at most the amplitude
            reach = np.linalg.norm(moved[starts[index] : starts[index + 1]] - cloud.bounding_sphere()[0], axis=1)
            assert np.max(reach + cloud.radii) <= rest_radii[index] + amplitude + 1e-9
            assert radius <= rest_radii[index] + amplitude + 1e-9


def test_the_shape_change_bound_holds_over_any_interval():
    wind = Wind(turbulence_m=25.0, turbulence_period_s=30.0)
    points = np.random.default_rng(3).normal(size=(300, 3)) * 400.0
    start = turbulent_offsets(wind, points, 100.0)
    for elapsed in (0.1, 1.0, 4.0, 60.0):
        changed = np.linalg.norm(turbulent_offsets(wind, points, 100.0 + elapsed) - start, axis=1).max()
        assert changed <= shape_change_bound_m(wind, elapsed) + 1e-9
    assert shape_change_bound_m(wind, math.inf) == 50.0 and shape_change_bound_m(None, 10.0) == 0.0


def test_a_field_s_grid_moves_with_the_air_and_its_cells_are_the_same():
    field = CloudField(seed=3, coverage=0.5, cell_size=800.0, rings=2)
    wind = Wind(bands=((0.0, 9.0, 315.0),))
    carried = field_drift(wind, field, 400.0)
    np.testing.assert_allclose(carried, drift(wind, [1900.0], 400.0)[0])
    eye = np.array([300.0, 1500.0, -200.0])
    # what the renderer draws: the cells for the eye's place relative to the air, carried on with it ...
    in_air, _ = update_field(field, eye - carried)
    drawn = np.concatenate([c.particles for c in in_air.clouds]) + np.append(carried, 0.0)
    # ... is the field whose grid starts where the air has carried its centre
    moved = dataclasses.replace(field, centre=(field.centre[0] + carried[0], field.centre[1] + carried[2]))
    expected, _ = update_field(moved, eye)
    np.testing.assert_allclose(drawn, np.concatenate([c.particles for c in expected.clouds]), atol=1e-6)
    np.testing.assert_array_equal(in_air.weights, expected.weights)
    assert len(drawn) > 100 and np.linalg.norm(carried) > 3000.0


def test_a_drift_of_the_cloud_is_measured_as_the_eye_s_step_the_other_way():
    units = LodUnits.of_spheres([[0.0, 1000.0, 0.0]], [300.0])
    made_from = (0.0, 1000.0, 5000.0)
    records = {(0,): ImpostorRecord(made_from, 64, 0, drift=(10.0, 0.0, 0.0), made_at_s=0.0)}
    drawable = np.array([0])
    eye = np.array(made_from)
    # the cloud has drifted 250 m east since (260 now against 10 then), its sphere with it
    moved = LodUnits.of_spheres([[250.0, 1000.0, 0.0]], [300.0])
    motion = CloudMotion(np.array([[260.0, 0.0, 0.0]]), 25.0, None, np.array([[10.0, 0.0, 0.0]]))
    error = held_impostor_errors(moved, drawable, records, parallax_errors_deg, eye, motion, np.array([[260.0, 0, 0]]))
    stepped = held_impostor_errors(units, drawable, records, parallax_errors_deg, eye - [250.0, 0.0, 0.0])
    np.testing.assert_allclose(error, stepped, rtol=1e-12)
    assert error[0] > 0.1
    # still air: no error while the eye stays
    assert held_impostor_errors(units, drawable, records, parallax_errors_deg, eye)[0] == 0.0


def test_turbulence_since_an_impostor_was_made_adds_its_angle():
    units = LodUnits.of_spheres([[0.0, 1000.0, 0.0]], [300.0])
    eye = np.array([0.0, 1000.0, 3300.0])
    records = {(0,): ImpostorRecord(tuple(eye), 64, 0, made_at_s=0.0)}
    wind = Wind(bands=((0.0, 0.0, 0.0),), turbulence_m=30.0, turbulence_period_s=60.0)
    motion = CloudMotion(np.zeros((1, 3)), 120.0, wind, np.zeros((1, 3)))
    error = held_impostor_errors(units, np.array([0]), records, parallax_errors_deg, eye, motion, np.zeros((1, 3)))
    np.testing.assert_allclose(error, [math.degrees(math.atan2(60.0, 3000.0))])


def test_turbulence_shortens_an_impostor_s_priced_life_as_it_grows_its_error():
    """A still eye: in still air an impostor lasts (the longest priced); under turbulence its error grows by the angle
    of a frame's change seen from the sphere's near side, until the tolerance, or not at all where the most it may
    change stays within it."""
    units = LodUnits.of_spheres([[0.0, 1000.0, 0.0]], [300.0])
    camera = Camera((0.0, 1000.0, 3300.0), (0.0, 1000.0, 0.0), 60.0)
    settings = RenderSettings(ring_radius=math.inf, tolerance_deg=0.5)
    pricing = pricing_of(camera, (640, 480), settings, LodState(eye=camera.position), ())
    still = seen_from(units, pricing).lifetimes[0]
    churning = seen_from(units, pricing, turbulence=(5.0, 60.0)).lifetimes[0]
    assert still == LONGEST_LIFETIME_FRAMES
    assert churning == pytest.approx(0.5 / math.degrees(5.0 / 3000.0), rel=1e-12)  # 5.2 frames
    # at most 10 m of change, 0.19 degrees from 3 km: the tolerance is never passed by it alone
    assert seen_from(units, pricing, turbulence=(5.0, 10.0)).lifetimes[0] == LONGEST_LIFETIME_FRAMES


def test_under_turbulence_an_impostor_whose_remaking_costs_more_than_it_saves_is_planned_full_3d():
    """One cloud 3 km off, a still eye, each regeneration 10 ms and full 3D 1 ms: in still air its impostor lasts and
    is the cheaper; under 30 m of turbulence at 2 s a frame it is remade every few frames, and auto mode heads to
    full 3D."""
    units = LodUnits.of_spheres([[0.0, 1000.0, 0.0]], [300.0], None, [1000.0], [1000.0 * 40.0**2])
    camera = Camera((0.0, 1000.0, 3300.0), (0.0, 1000.0, 0.0), 60.0)
    settings = RenderSettings(mode="auto", ring_radius=math.inf)
    costs = CostModel(particles=1e-3, fragments=1e-9, texture_fragments=1e-9, quad_pixels=1e-9, regenerations=10.0)
    churn = Wind(bands=((0.0, 0.0, 0.0),), turbulence_m=30.0, turbulence_period_s=60.0)
    targets = {}
    for name, wind in (("still air", None), ("churn", churn)):
        state = LodState()
        for time_s in (0.0, 2.0, 4.0):
            motion = CloudMotion(np.zeros((1, 3)), time_s, wind, np.zeros((1, 3)))
            planned = plan_frame(units, camera, (640, 480), settings, state, 1, costs=costs, motion=motion)
            state = planned.state
        targets[name] = (state.representations[(0,)].target, planned.clouds[0].impostor_ms)
    assert targets["still air"][0] == "impostor" and targets["churn"][0] == "full"
    assert targets["churn"][1] > 10.0 * targets["still air"][1]


FILE = """
[wind]
bands = [[0.0, 8.0, 250.0], [3000.0, 20.0, 280.0]]
gust_amplitude = 0.3
gust_period_s = 45.0
turbulence_m = 40.0
"""


def test_the_table_reads_saves_and_reads_again(tmp_path):
    path = tmp_path / "windy.toml"
    path.write_text(FILE)
    scene = load_scene(path)
    assert scene.wind == Wind(
        bands=((0.0, 8.0, 250.0), (3000.0, 20.0, 280.0)), gust_amplitude=0.3, gust_period_s=45.0, turbulence_m=40.0
    )
    save_scene(scene, tmp_path / "again.toml")
    assert load_scene(tmp_path / "again.toml").wind == scene.wind
    assert load_scene(DEFAULT_SCENE).wind is None
    save_scene(Scene(), tmp_path / "still.toml")
    assert "wind" not in (tmp_path / "still.toml").read_text()
    assert TABLE_KEYS["wind"] == tuple(f.name for f in dataclasses.fields(Wind))


@pytest.mark.parametrize(
    "line, field, problem",
    [
        ("bands = [[0.0, 101.0, 0.0]]", "wind.bands", "row 0: speed must be within [0, 100] m/s, got 101.0"),
        ("bands = [[0.0, 5.0, -1.0]]", "wind.bands", "row 0: direction must be within [0, 360] degrees, got -1.0"),
        ("bands = [[0.0, 5.0, 10.0], [0.0, 5.0, 10.0]]", "wind.bands", "altitudes must increase from row to row"),
        ("bands = []", "wind.bands", "expected rows of 3 numbers, got shape (0,)"),
        ("bands = [[0.0, 5.0]]", "wind.bands", "expected rows of 3 numbers, got shape (1, 2)"),
        ("bands = [[nan, 5.0, 10.0]]", "wind.bands", "row 0 is not finite: [nan, 5.0, 10.0]"),
        ("gust_amplitude = 1.5", "wind.gust_amplitude", "must be within [0, 1], got 1.5"),
        ("gust_period_s = 0.0", "wind.gust_period_s", "must be within [1, 3600], got 0.0"),
        ("turbulence_m = 501.0", "wind.turbulence_m", "must be within [0, 500], got 501.0"),
        ("turbulence_scale_m = 1.0", "wind.turbulence_scale_m", "must be within [10, 10000], got 1.0"),
        ("turbulence_period_s = inf", "wind.turbulence_period_s", "must be finite, got inf"),
        ("relight_period_s = 0.1", "wind.relight_period_s", "must be within [0.5, 3600], got 0.1"),
        ("gusts = 1.0", "wind.gusts", "unknown key; valid keys: " + ", ".join(TABLE_KEYS["wind"])),
        ('turbulence_m = "a lot"', "wind.turbulence_m", "expected a number, got 'a lot'"),
    ],
)
def test_every_key_is_refused_in_one_line_naming_file_and_field(tmp_path, line, field, problem):
    path = tmp_path / "bad.toml"
    path.write_text(f"[wind]\n{line}\n")
    assert_file_refused_in_one_line(path, field, problem)


def test_the_cli_refuses_a_bad_wind_in_one_line_with_status_2(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[wind]\nbands = [[0.0, 500.0, 90.0]]\n")
    result = subprocess.run([sys.executable, "-m", "cloudcore.cli", "shade", str(path)], capture_output=True, text=True)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        f"cloudview: error: {path}: wind.bands: row 0: speed must be within [0, 100] m/s, got 500.0"
    ]


@pytest.mark.parametrize(
    "change, field",
    [
        ({"bands": ((0.0, 5.0, 400.0),)}, "bands"),
        ({"bands": ()}, "bands"),
        ({"bands": ((0.0, 5.0),)}, "bands"),
        ({"gust_amplitude": float("nan")}, "gust_amplitude"),
        ({"turbulence_m": True}, "turbulence_m"),
    ],
)
def test_the_record_refuses_what_the_file_would_so_the_editor_s_edits_are_checked_too(change, field):
    with pytest.raises(FieldError) as caught:
        dataclasses.replace(Wind(), **change)
    assert caught.value.field == field


def test_a_scene_dict_without_wind_has_still_air():
    assert scene_from_dict({}).wind is None


def test_the_ground_s_shadow_map_moves_with_clouds_all_drifting_alike():
    rng = np.random.default_rng(8)
    centres, radii = rng.normal(size=(300, 3)) * 400.0 + [0.0, 1500.0, 0.0], rng.uniform(40.0, 90.0, 300)
    sun = (0.3, 0.8, -0.52)
    shift = np.array([640.0, 0.0, -210.0])
    space = light_space(centres, radii, sun, 256)
    ground = rng.uniform(-3000.0, 3000.0, size=(50, 3)) * [1.0, 0.0, 1.0]
    # a point under the moved clouds reads the texel and slice its place less the shift read under them at rest
    for moved, at_rest in zip(space.moved(shift).texel_coordinates(ground + shift), space.texel_coordinates(ground)):
        np.testing.assert_allclose(moved, at_rest, atol=1e-9)


def test_an_impostor_of_a_drifting_cloud_is_priced_to_last_as_long_as_the_eye_s_step_relative_to_it():
    units = LodUnits.of_spheres([[0.0, 1000.0, -4000.0]], [400.0])
    camera = Camera((0.0, 1000.0, 0.0), (0.0, 1000.0, -4000.0), 60.0)
    settings = RenderSettings(ring_radius=math.inf)
    still_eye = LodState(eye=camera.position)
    # a still eye and a cloud carried 20 m east in the frame ...
    drifting = seen_from(
        units, pricing_of(camera, (640, 480), settings, still_eye, ()), air_steps=np.array([[20.0, 0, 0]])
    )
    # ... is the cloud at rest and an eye that stepped 20 m west
    stepped = LodState(eye=(20.0, 1000.0, 0.0))
    moving = seen_from(units, pricing_of(camera, (640, 480), settings, stepped, ()))
    assert np.isfinite(drifting.lifetimes[0]) and drifting.lifetimes[0] == pytest.approx(moving.lifetimes[0], rel=1e-12)
    still_air = seen_from(units, pricing_of(camera, (640, 480), settings, still_eye, ()))
    assert still_air.lifetimes[0] > 2.0 * drifting.lifetimes[0]
