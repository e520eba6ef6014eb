"""Generated clouds: Wang's box fill with a cull distance, and the named cloud types built from it."""

import dataclasses
import time

import numpy as np
import pytest
from scipy.spatial import cKDTree

from cloudcore.artist.artist_shading import height_fractions
from cloudcore.artist.cloudgen import PRESETS, box_fill, cull_close, preset_cloud
from cloudcore.artist.sprites import particle_sprites
from cloudcore.model.cloud_records import ATLAS_GRID, FLAT_BOTTOM, FOGGY, WISPY
from cloudcore.model.scene import Cloud

LOW, HIGH = np.array([-500.0, 1000.0, -300.0]), np.array([700.0, 1400.0, 500.0])


def closest_gap(positions: np.ndarray) -> float:
    """The smallest distance between two of `positions`."""
    distances, _ = cKDTree(positions).query(positions, k=2)
    return float(distances[:, 1].min())


def test_box_fill_keeps_particles_inside_the_box_and_apart():
    particles = box_fill(LOW, HIGH, particle_radius=60.0, count=800, seed=5)
    assert particles.shape[1] == 4 and particles.dtype == np.float64
    assert np.all(particles[:, :3] >= LOW) and np.all(particles[:, :3] <= HIGH)
    assert np.all(particles[:, 3] == 60.0)
    assert closest_gap(particles[:, :3]) > 40.0  # default cull distance: a third of the sprite size, 2 r / 3
    assert 300 < len(particles) < 800  # some culled, most kept


@pytest.mark.parametrize("cull_distance", [0.0, 10.0, 120.0, 400.0])
def test_no_two_kept_particles_are_within_the_cull_distance(cull_distance):
    particles = box_fill(LOW, HIGH, 60.0, 600, cull_distance=cull_distance, seed=2)
    if cull_distance == 0.0:
        assert len(particles) == 600
    else:
        assert closest_gap(particles[:, :3]) > cull_distance


def test_box_fill_is_deterministic_for_a_seed():
    np.testing.assert_array_equal(box_fill(LOW, HIGH, 60.0, 500, seed=9), box_fill(LOW, HIGH, 60.0, 500, seed=9))
    assert not np.array_equal(box_fill(LOW, HIGH, 60.0, 500, seed=9), box_fill(LOW, HIGH, 60.0, 500, seed=10))


def test_culling_walks_the_list_in_order_like_wang():
    # 0 and 1 are close, 1 and 2 are close, 0 and 2 are not: 1 goes, 0 and 2 stay
    positions = np.array([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0], [1.6, 0.0, 0.0], [5.0, 0.0, 0.0], [5.0, 0.5, 0.0]])
    np.testing.assert_array_equal(cull_close(positions, 1.0), [0, 2, 3])
    np.testing.assert_array_equal(cull_close(positions[::-1], 1.0), [0, 2, 4])


def test_culling_is_greedy_and_maximal():
    """Every dropped particle is within the cull distance of a kept one that comes earlier."""
    positions = np.random.default_rng(1).uniform(0.0, 10.0, (2000, 3))
    kept = cull_close(positions, 0.7)
    dropped = np.setdiff1d(np.arange(len(positions)), kept)
    for i in dropped:
        earlier = kept[kept < i]
        assert np.linalg.norm(positions[earlier] - positions[i], axis=1).min() <= 0.7


@pytest.mark.parametrize("count", [0, 1, 2])
def test_tiny_and_empty_fills(count):
    particles = box_fill(LOW, HIGH, 60.0, count, cull_distance=1e-9, seed=1)
    assert particles.shape == (count, 4)


def test_a_flat_box_and_a_point_box_are_allowed():
    flat = box_fill([0.0, 500.0, 0.0], [1000.0, 500.0, 1000.0], 30.0, 200, seed=1)
    assert np.all(flat[:, 1] == 500.0)
    point = box_fill([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], 30.0, 50, seed=1)
    np.testing.assert_array_equal(point, [[1.0, 2.0, 3.0, 30.0]])  # all coincide: the first is kept


def test_ten_thousand_candidates_take_well_under_a_second():
    start = time.perf_counter()
    particles = box_fill([0.0, 0.0, 0.0], [2000.0, 600.0, 2000.0], 40.0, 10_000, seed=3)
    assert time.perf_counter() - start < 0.5
    assert closest_gap(particles[:, :3]) > 40.0 * 2.0 / 3.0


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(box_max=[0.0, 0.0, 0.0]), "box_max"),
        (dict(box_min=[0.0, np.nan, 0.0]), "finite"),
        (dict(box_min=[-1.7e308, 0.0, 0.0], box_max=[1.7e308, 1.0, 1.0]), "finite"),
        (dict(box_min=[0.0, 0.0]), "3-vectors"),
        (dict(particle_radius=0.0), "particle_radius"),
        (dict(particle_radius=np.inf), "particle_radius"),
        (dict(count=-1), "count"),
        (dict(count=2.5), "count"),
        (dict(cull_distance=-1.0), "cull_distance"),
        (dict(cull_distance=np.nan), "cull_distance"),
    ],
)
def test_bad_box_fill_input_is_refused(change, message):
    arguments = dict(box_min=LOW, box_max=HIGH, particle_radius=60.0, count=10) | change
    with pytest.raises(ValueError, match=message):
        box_fill(**arguments)


# ---------------------------------------------------------------- presets


def extent(cloud: Cloud) -> np.ndarray:
    return np.ptp(cloud.centres, axis=0) + 2.0 * cloud.radii.max()


@pytest.fixture(scope="module")
def clouds() -> dict[str, Cloud]:
    return {name: preset_cloud(name, name, (100.0, 1200.0, -50.0), seed=4) for name in PRESETS}


def test_presets_cover_wangs_cloud_types():
    assert set(PRESETS) == {
        "cumulus_humilis",
        "cumulus_congestus",
        "stratus",
        "stratocumulus",
        "cumulonimbus",
        "altocumulus",
        "cirrus",
    }


def test_each_preset_is_a_sensible_cloud_in_its_boxes(clouds):
    for name, cloud in clouds.items():
        preset = PRESETS[name]
        assert isinstance(cloud, Cloud) and cloud.name == name
        assert preset.count // 3 < len(cloud.particles) <= preset.count, name
        size = np.asarray(preset.size)
        low = np.array([100.0, 1200.0, -50.0]) - [size[0] / 2, 0.0, size[2] / 2]
        assert np.all(cloud.centres >= low) and np.all(cloud.centres <= low + size), name
        assert closest_gap(cloud.centres) > preset.cull_fraction * 2.0 * preset.particle_radius, name
        assert (cloud.optical_depth, cloud.albedo, cloud.color) == (preset.optical_depth, preset.albedo, preset.color)


def test_presets_differ_the_way_the_cloud_types_do(clouds):
    width = {n: max(extent(c)[0], extent(c)[2]) for n, c in clouds.items()}
    height = {n: extent(c)[1] for n, c in clouds.items()}
    assert width["stratus"] > 8 * height["stratus"]  # wide and flat
    assert height["cumulonimbus"] > width["cumulonimbus"]  # tall
    assert height["cumulonimbus"] == max(height.values())
    assert height["cumulus_congestus"] > width["cumulus_congestus"] > width["cumulus_humilis"]
    assert width["stratus"] == max(width.values())
    assert clouds["altocumulus"].radii.max() == min(c.radii.max() for c in clouds.values())  # small puffs
    depth = {n: c.optical_depth for n, c in clouds.items()}
    assert min(depth, key=depth.get) == "cirrus"  # thin veils
    assert clouds["stratus"].optical_depth == min(d for n, d in depth.items() if n != "cirrus")  # most transparent
    assert clouds["cumulonimbus"].optical_depth == max(c.optical_depth for c in clouds.values())
    brightness = {n: sum(c.color) for n, c in clouds.items()}
    assert min(brightness, key=brightness.get) == "cumulonimbus"  # dark
    assert max(brightness, key=brightness.get) == "cumulus_humilis"  # nearly white
    # the anvil: the top of a cumulonimbus is wider than its middle
    cb = clouds["cumulonimbus"]
    y = (cb.centres[:, 1] - 1200.0) / PRESETS["cumulonimbus"].size[1]
    assert np.ptp(cb.centres[y > 0.9, 0]) > 1.4 * np.ptp(cb.centres[(y > 0.4) & (y < 0.6), 0])


def test_preset_scale_scales_the_same_shape():
    unit = preset_cloud("cumulus_humilis", "a", (0.0, 0.0, 0.0), scale=1.0, seed=7)
    double = preset_cloud("cumulus_humilis", "a", (0.0, 0.0, 0.0), scale=2.0, seed=7)
    np.testing.assert_allclose(double.particles, 2.0 * unit.particles, rtol=1e-12)


def test_presets_are_deterministic_for_a_seed():
    assert preset_cloud("stratus", "s", (0.0, 500.0, 0.0), seed=1) == preset_cloud(
        "stratus", "s", (0.0, 500.0, 0.0), seed=1
    )


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: preset_cloud("nimbostratus", "c", (0.0, 0.0, 0.0)), "stratus"),
        (lambda: preset_cloud("stratus", "c", (0.0, 0.0, 0.0), scale=0.0), "scale"),
        (lambda: preset_cloud("stratus", "c", (0.0, 0.0, 0.0), scale=1e306), "finite"),
        (lambda: preset_cloud("stratus", "c", (0.0, np.nan, 0.0)), "base_centre"),
    ],
)
def test_bad_preset_input_is_refused(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# ---------------------------------------------------------------- presets: sprites and artist shading


def test_each_preset_cloud_carries_its_sprites_and_artist_model(clouds):
    for name, cloud in clouds.items():
        assert cloud.sprite == dataclasses.replace(PRESETS[name].sprite, seed=4), name
        assert cloud.artist == PRESETS[name].artist, name
    assert preset_cloud("stratus", "s", (0.0, 0.0, 0.0), seed=9).sprite.seed == 9


def test_cumulus_presets_have_flat_bottoms_turned_only_a_little(clouds):
    """Wang 3.2: flat-bottomed textures make cumulus bases, within a few degrees of upright; other sprites
    turn the full circle."""
    for name in ("cumulus_humilis", "cumulus_congestus", "stratocumulus", "cumulonimbus"):
        cloud = clouds[name]
        indices, rotations = particle_sprites(cloud.sprite, cloud.centres)
        y = cloud.centres[:, 1]
        base = height_fractions(y, y.min(), y.max()) <= cloud.sprite.flat_bottom_fraction
        assert base.any() and (~base).any(), name
        assert np.all(indices[base] // ATLAS_GRID == FLAT_BOTTOM), name
        assert np.all(indices[~base] // ATLAS_GRID != FLAT_BOTTOM), name
        assert np.all(np.abs(np.degrees(rotations[base])) <= 5.0), name
        assert np.ptp(np.degrees(rotations[~base])) > 300.0, name


def test_stratus_is_mostly_foggy_and_cirrus_is_flat_wisps(clouds):
    stratus = clouds["stratus"]
    rows = particle_sprites(stratus.sprite, stratus.centres)[0] // ATLAS_GRID
    assert np.mean(rows == FOGGY) > 0.6
    cirrus = clouds["cirrus"]
    indices, rotations = particle_sprites(cirrus.sprite, cirrus.centres)
    assert cirrus.sprite.facing == "horizontal"
    assert np.all(indices // ATLAS_GRID == WISPY)
    assert np.all(np.abs(np.degrees(rotations)) <= 20.0)  # combed one way by the wind
    assert all(c.sprite.facing == "camera" for n, c in clouds.items() if n != "cirrus")


def test_preset_colour_levels_follow_wang(clouds):
    """Wang 5.1: humilis nearly uniformly white, cumulonimbus dark from top to bottom, stratus light grey and
    more transparent; every type darker at the base."""
    levels = {n: np.array(c.artist.levels) for n, c in clouds.items()}
    grey = {n: level[:, 1:4].mean(axis=1) for n, level in levels.items()}  # (5,) bottom to top
    alpha = {n: level[:, 4].mean() for n, level in levels.items()}
    assert grey["cumulus_humilis"].min() > 0.6 and np.ptp(grey["cumulus_humilis"]) < 0.25
    for name, g in grey.items():
        assert np.all(np.diff(g) >= 0.0), name
        if name != "cumulonimbus":
            assert np.all(grey["cumulonimbus"] < g), name
    assert grey["cumulus_congestus"][-1] - grey["cumulus_congestus"][0] > 0.3  # grey base, white top
    assert 0.4 < grey["stratus"].mean() < 0.7 and alpha["stratus"] < 0.6
    assert alpha["stratus"] < min(alpha[n] for n in levels if n not in ("stratus", "cirrus"))
