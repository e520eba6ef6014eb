"""The cloud field (Yusov 2014, section 5.2): deterministic cells, incremental rings, cost by rings, no popping."""

import dataclasses
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from cloudcore.field.cells import CANDIDATES_PER_SIDE, cell_cloud, cell_clouds, cloud_density, coverage_threshold
from cloudcore.field.grid import (
    RING_HALF_CELLS,
    cell_side,
    cells_in_reach,
    level_reach,
    level_support,
    level_weights,
)
from cloudcore.field.state import FADE_KEY_STEPS, HOLE, FieldState, update_field
from cloudcore.model.errors import FieldError
from cloudcore.model.scene import MAX_RINGS, CloudField, Scene
from cloudcore.resources import CUMULUS_FIELD, DEFAULT_SCENE
from cloudcore.scenes.files import TABLE_KEYS, load_scene, save_scene

FIELD = CloudField(seed=3, coverage=0.5, cell_size=500.0, rings=4, layers=3, extent=(60000.0, 60000.0))
EYE = np.array([130.0, 2000.0, -270.0])


def test_a_cell_is_the_same_particles_whenever_it_is_made():
    first = cell_cloud(FIELD, 1, 3, -2)
    again = cell_cloud(dataclasses.replace(FIELD), 1, 3, -2)
    assert first is not None and len(first.particles) > 0
    np.testing.assert_array_equal(first.particles, again.particles)
    # and made again by a fresh state, from another eye, it is the same too
    _, state = update_field(FIELD, EYE)
    _, elsewhere = update_field(FIELD, EYE + [700.0, 0.0, 300.0])
    for key in set(state.cells) & set(elsewhere.cells):
        a, b = state.cells[key], elsewhere.cells[key]
        assert (a is None) == (b is None)
        if a is not None:
            np.testing.assert_array_equal(a.particles, b.particles)


def test_a_cell_made_with_others_is_the_cell_made_alone():
    cells = [(2, 0, 0), (0, 1, -1), (0, -3, 2), (1, 1, 1), (0, 0, 0)]
    for cell, cloud in zip(cells, cell_clouds(FIELD, cells)):
        alone = cell_cloud(FIELD, *cell)
        assert (cloud is None) == (alone is None)
        if cloud is not None:
            np.testing.assert_array_equal(cloud.particles, alone.particles)
            assert cloud.name == alone.name == "field_{}_{}_{}".format(*cell)


def test_another_seed_makes_other_clouds():
    other = dataclasses.replace(FIELD, seed=4)
    a, b = cell_cloud(FIELD, 0, 0, 0), cell_cloud(other, 0, 0, 0)
    assert a is None or b is None or not np.array_equal(a.particles, b.particles)


def test_particles_stay_in_their_cell_and_altitude_band_and_coarser_cells_have_larger_particles():
    radii = []
    for level in range(FIELD.rings):
        side = cell_side(FIELD, level)
        clouds = []
        for i in range(-2, 2):
            for j in range(-2, 2):
                cloud = cell_cloud(FIELD, level, i, j)
                if cloud is None:
                    continue
                x, y, z = cloud.centres.T
                assert np.all((x >= i * side) & (x <= (i + 1) * side) & (z >= j * side) & (z <= (j + 1) * side))
                assert np.all((y >= FIELD.altitude[0]) & (y <= FIELD.altitude[1]))
                clouds.append(cloud)
        radii.append(np.median(np.concatenate([c.radii for c in clouds])))
    # Yusov: particle size follows the cell size (twice the cell, twice the particle)
    np.testing.assert_allclose(np.array(radii[1:]) / radii[:-1], 2.0, rtol=0.15)


def test_higher_layers_are_smaller_and_fewer():
    # towers (congestus) that reach the band's top: a humilis of these 500 m cells is a few hundred metres tall
    field = dataclasses.replace(FIELD, cloud_type="cumulus_congestus")
    cloud_rows = [cell_cloud(field, 0, i, j) for i in range(-6, 6) for j in range(-6, 6)]
    particles = np.concatenate([c.particles for c in cloud_rows if c is not None])
    bottom, top = field.altitude
    layer = np.minimum(((particles[:, 1] - bottom) / (top - bottom) * field.layers).astype(int), field.layers - 1)
    counts = np.bincount(layer, minlength=field.layers)
    assert np.all(np.diff(counts) < 0)  # narrower tops
    sizes = [particles[layer == k, 3].mean() for k in range(field.layers)]
    assert np.all(np.diff(sizes) < 0)


@pytest.mark.parametrize("coverage", [0.1, 0.4, 0.8])
def test_coverage_is_the_share_of_the_plane_that_is_cloudy(coverage):
    x, z = np.meshgrid(np.linspace(-3e4, 3e4, 300), np.linspace(-3e4, 3e4, 300))
    cloudy = np.mean(cloud_density(FIELD, x, z) > coverage_threshold(coverage))
    assert abs(cloudy - coverage) < 0.08


def test_no_coverage_no_clouds_and_full_coverage_clouds_everywhere():
    assert update_field(dataclasses.replace(FIELD, coverage=0.0), EYE)[0].particle_count == 0
    overcast = dataclasses.replace(FIELD, coverage=1.0, layers=1)
    cloud = cell_cloud(overcast, 0, 0, 0)
    assert len(cloud.particles) == CANDIDATES_PER_SIDE**2  # every candidate of the one layer


def test_moving_one_inner_cell_makes_only_the_cells_entering_a_ring():
    _, state = update_field(FIELD, EYE)
    before = dict(state.cells)
    moved = EYE + [FIELD.cell_size, 0.0, 0.0]
    _, after = update_field(FIELD, moved, state)
    assert after.made, "a whole inner cell of travel brings new cells into the inner ring"
    for key in after.made:
        assert key not in before
        assert key[1:] in cells_in_reach(FIELD, key[0], moved)
    # the inner ring gains one column of cells, at the front
    inner = [key for key in after.made if key[0] == 0]
    assert len(inner) <= 2 * RING_HALF_CELLS + 2
    assert all(key[1] * FIELD.cell_size - FIELD.centre[0] > moved[0] for key in inner)
    # everything else is the very same clouds (the illumination cache knows them by identity)
    for key, cloud in after.cells.items():
        if key in before:
            assert cloud is before[key]
    assert len(after.made) < 0.25 * len(after.cells)
    # a still eye makes nothing
    _, again = update_field(FIELD, moved, after)
    assert again.made == () and again.dropped == 0 and again.cells == after.cells


def test_clouds_that_stay_keep_their_places_in_the_frame():
    frame, state = update_field(FIELD, EYE)
    places = {id(c): i for i, c in enumerate(frame.clouds) if c is not HOLE}
    for step in range(1, 6):
        frame, state = update_field(FIELD, EYE + [step * 0.4 * FIELD.cell_size, 0.0, 0.0], state)
        for i, cloud in enumerate(frame.clouds):
            if id(cloud) in places and cloud is not HOLE:
                assert places[id(cloud)] == i
        places = {id(c): i for i, c in enumerate(frame.clouds) if c is not HOLE}
    assert len(frame.weights) == sum(len(c.particles) for c in frame.clouds)


def test_a_changed_field_is_made_anew():
    _, state = update_field(FIELD, EYE)
    denser = dataclasses.replace(FIELD, coverage=0.7)
    _, again = update_field(denser, EYE, state)
    assert again.field == denser and set(again.made) == set(again.cells)


def test_cost_grows_with_the_rings_not_with_the_field_s_extent():
    counts = {}
    for extent in (1e5, 4e5, 1.6e6):
        field = dataclasses.replace(FIELD, extent=(extent, extent))
        frame, state = update_field(field, EYE)
        counts[extent] = (frame.particle_count, len(state.cells))
    reach = level_reach(FIELD, FIELD.rings - 1)
    assert reach < 0.5e5  # every extent holds all the rings
    assert len(set(counts.values())) == 1
    cells = [len(update_field(dataclasses.replace(FIELD, rings=rings), EYE)[1].cells) for rings in range(1, 6)]
    assert all(np.diff(cells) > 0)
    per_ring = (2 * RING_HALF_CELLS + 2) ** 2
    assert all(c <= rings * per_ring for c, rings in zip(cells, range(1, 6)))


def test_an_eye_far_outside_the_field_makes_nothing():
    for eye in ([1e7, 2000.0, 0.0], [1e300, 0.0, -1e300], [-1e308, 0.0, 0.0]):
        frame, state = update_field(FIELD, eye)
        assert frame.particle_count == 0 and not state.cells


def test_weights_sum_to_one_across_each_level_change_and_vanish_at_the_ends():
    distance = np.linspace(0.0, 1.2 * level_reach(FIELD, FIELD.rings - 1), 5001)
    total = sum(
        level_weights(FIELD, np.full(distance.shape, level), EYE[0] + distance, np.full(distance.shape, EYE[2]), EYE)
        for level in range(FIELD.rings)
    )
    inside = distance < level_reach(FIELD, FIELD.rings - 1) - cell_side(FIELD, FIELD.rings - 1)
    np.testing.assert_allclose(total[inside], 1.0, atol=1e-12)
    assert total[-1] == 0.0
    for level in range(FIELD.rings):
        lo, hi = level_support(FIELD, level)
        w = level_weights(
            FIELD, np.full(distance.shape, level), EYE[0] + distance, np.full(distance.shape, EYE[2]), EYE
        )
        assert np.all(w[(distance <= lo) | (distance >= hi)] == 0.0)
        assert np.all(np.isfinite(w)) and w.min() >= 0.0 and w.max() <= 1.0


def _region_opacity(field, eye, state, low, high):
    """The region's weighted opacity (sum of weight x splat area over the particles centred in it): what its mean
    brightness follows, seen from above."""
    frame, state = update_field(field, eye, state)
    particles = np.concatenate([c.particles for c in frame.clouds]) if frame.clouds else np.zeros((0, 4))
    x, z = particles[:, 0], particles[:, 2]
    inside = (x >= low[0]) & (x < high[0]) & (z >= low[1]) & (z < high[1])
    return float(np.sum(frame.weights[inside] * np.pi * particles[inside, 3] ** 2)), state


def test_no_popping_a_cell_s_region_changes_smoothly_as_it_changes_level():
    """Flying away from a region of one level-2 cell, it goes from the inner ring's cells to level 1's, 2's and 3's
    (and to nothing as the last ring fades toward the horizon): its weighted opacity must never jump between two eye
    positions a few metres apart."""
    field = dataclasses.replace(FIELD, coverage=0.6)
    side = cell_side(field, 2)
    low, high = np.array([0.0, 0.0]), np.array([side, side])
    # on until the region's nearest point (half its side from its centre) is past the last ring's reach
    steps = np.arange(0.0, level_reach(field, 3) + 0.5 * side + 0.02 * field.cell_size, 0.02 * field.cell_size)
    state, values = FieldState(), []
    for step in steps:
        value, state = _region_opacity(field, np.array([0.5 * side - step, 2000.0, 0.5 * side]), state, low, high)
        values.append(value)
    values = np.array(values)
    assert values.max() > 0
    jumps = np.abs(np.diff(values)) / values.max()
    # a region crossing a blend band changes by a few per cent a step; a popping cell would change by a cell's share
    assert jumps.max() < 0.03
    # and each level shows about as much cloud as the next, until the last ring's fade toward the horizon
    before_horizon = steps + side < level_reach(field, 3) - cell_side(field, 3)
    assert values[before_horizon].min() > 0.75 * values[before_horizon].max()
    assert values[-1] == 0.0


def test_the_popping_test_can_fail_without_the_blend():
    """The same measure with the weights rounded to 0 or 1 (hard switches between levels) jumps."""
    field = dataclasses.replace(FIELD, coverage=0.6)
    side = cell_side(field, 2)
    state, values = FieldState(), []
    for step in np.arange(0.0, level_reach(field, 3) - side, 0.02 * field.cell_size):
        eye = np.array([0.5 * side - step, 2000.0, 0.5 * side])
        frame, state = update_field(field, eye, state)
        particles = np.concatenate([c.particles for c in frame.clouds])
        inside = (particles[:, 0] >= 0) & (particles[:, 0] < side) & (particles[:, 2] >= 0) & (particles[:, 2] < side)
        hard = np.round(frame.weights[inside])
        values.append(float(np.sum(hard * particles[inside, 3] ** 2)))
    values = np.array(values)
    assert (np.abs(np.diff(values)) / values.max()).max() > 0.1


def test_a_cloud_s_fade_key_is_its_mean_weight_rounded_up_to_a_step_and_exactly_1_when_it_does_not_blend():
    frame, state = update_field(FIELD, EYE)
    starts = state.cloud_starts
    for index, key in enumerate(frame.fade_keys):
        weights = frame.weights[starts[index] : starts[index + 1]]
        assert frame.mean_weights[index] == pytest.approx(weights.mean() if len(weights) else 1.0, abs=1e-12)
        if np.all(weights == 1.0):
            assert key == 1.0
        else:
            assert weights.mean() <= key < weights.mean() + 1.0 / FADE_KEY_STEPS + 1e-12
            assert (key == 0.0) == (weights.mean() == 0.0)  # an empty impostor is never scaled up
    assert 1.0 in frame.fade_keys and min(frame.fade_keys) < 1.0


# ---------------------------------------------------------------- the scene file

DEMO_TABLE = """
[cloud_field]
seed = 7
coverage = 0.3
cell_size = 800.0
rings = 3
layers = 2
altitude = [1000.0, 2000.0]
cloud_type = "cumulus_congestus"
extent = [50000.0, 40000.0]
centre = [100.0, -200.0]
"""


def test_the_field_round_trips_through_the_scene_file(tmp_path):
    path = tmp_path / "field.toml"
    path.write_text(DEMO_TABLE)
    scene = load_scene(path)
    assert scene.cloud_field == CloudField(
        7, 0.3, 800.0, 3, 2, (1000.0, 2000.0), "cumulus_congestus", (50000.0, 40000.0), (100.0, -200.0)
    )
    saved = save_scene(scene, tmp_path / "again.toml")
    assert load_scene(tmp_path / "again.toml") == saved == scene
    assert list(tomllib.loads((tmp_path / "again.toml").read_text())["cloud_field"]) == list(TABLE_KEYS["cloud_field"])
    # the file holds parameters, not particles
    assert not list(tmp_path.glob("*.particles"))


def test_a_scene_without_a_field_saves_without_one(tmp_path):
    path = tmp_path / "plain.toml"
    save_scene(Scene(), path)
    assert "cloud_field" not in path.read_text() and load_scene(path).cloud_field is None


def test_the_cli_refuses_a_bad_field_in_one_line_with_status_2(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(DEMO_TABLE.replace("rings = 3", "rings = 0"))
    result = subprocess.run([sys.executable, "-m", "cloudcore.cli", "shade", str(path)], capture_output=True, text=True)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        f"cloudview: error: {path}: cloud_field.rings: must be within [1, {MAX_RINGS}], got 0"
    ]


def test_the_demo_scene_is_a_field_100_km_across_with_a_flight_at_2_km_and_is_not_the_default():
    scene = load_scene(CUMULUS_FIELD)
    assert scene.cloud_field.extent == (100000.0, 100000.0)
    assert scene.cloud_field.cloud_type.startswith("cumulus")
    keys = scene.camera_path("flight").keys
    assert keys[0, 2] == 2000.0 and keys[:, 2].max() > scene.cloud_field.altitude[1]  # through, then above
    assert np.linalg.norm(np.diff(keys[:, 1:4], axis=0), axis=1).sum() >= 20000.0
    assert DEFAULT_SCENE != CUMULUS_FIELD


@pytest.mark.parametrize(
    "change, field",
    [
        ({"rings": 0}, "rings"),
        ({"layers": True}, "layers"),
        ({"coverage": float("nan")}, "coverage"),
        ({"cell_size": 5.0}, "cell_size"),
        ({"altitude": (1.0, 1.0)}, "altitude"),
        ({"extent": (1e3, float("inf"))}, "extent"),
        ({"centre": (0.0,)}, "centre"),
    ],
)
def test_the_record_refuses_what_the_file_would_so_the_editor_s_edits_are_checked_too(change, field):
    with pytest.raises(FieldError) as caught:
        dataclasses.replace(FIELD, **change)
    assert caught.value.field == field
