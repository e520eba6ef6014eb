"""The default scene: what issue 2 promises about cloudcore/resources/scenes/valley.toml."""

import numpy as np
import pytest

from cloudcore.maths.paths import sample
from cloudcore.scenes.files import load_scene
from cloudcore.world.sun import elevation_deg, sun_direction
from cloudcore.world.terrain import height_at, heightfield_mesh
from tests.conftest import VALLEY


@pytest.fixture(scope="module")
def valley():
    return load_scene(VALLEY)


def inside_clouds(scene, point):
    """Names of the clouds with a particle whose core (half radius) contains `point`."""
    return {c.name for c in scene.clouds if np.any(np.linalg.norm(c.centres - point, axis=1) < 0.5 * c.radii)}


def test_after_harris_figure_3(valley):
    assert len(valley.clouds) == 34
    assert 85_000 <= valley.particle_count <= 95_000
    vertices, faces = heightfield_mesh(valley.terrain)
    assert 55_000 <= len(faces) <= 65_000
    assert np.all(np.isfinite(vertices))
    assert elevation_deg(sun_direction(valley.lighting.time_of_day)) > 10  # afternoon sun, well up
    assert 12 < valley.lighting.time_of_day < 18


def test_clouds_hang_low_over_the_valley_between_mountains(valley):
    """Harris's figure 3: the valley's floor under every cloud, mountains beside it higher than the clouds."""
    for cloud in valley.clouds:
        under = height_at(valley.terrain, cloud.centres[:, 0], cloud.centres[:, 2])
        assert np.all(cloud.centres[:, 1] - cloud.radii > under + 200.0), cloud.name
    highest_cloud = max(float((c.centres[:, 1] + c.radii).max()) for c in valley.clouds)
    x, z = np.meshgrid(np.linspace(-12_000.0, 12_000.0, 97), np.linspace(-12_000.0, 12_000.0, 97))
    assert height_at(valley.terrain, x, z).max() > 1.3 * highest_cloud


def test_flythrough_lasts_about_30_s_and_passes_through_two_clouds(valley):
    path = valley.camera_path("flythrough")
    assert 25 <= path.duration <= 35
    visited = set()
    for t in np.arange(path.keys[0, 0], path.keys[-1, 0], 0.05):
        visited |= inside_clouds(valley, sample(path.keys, t)[:3])
    assert len(visited) >= 2


def test_aircraft_path_crosses_a_cloud(valley):
    (aircraft,) = [o for o in valley.objects if o.primitive == "aircraft"]
    crossed = set()
    for t in np.arange(aircraft.path[0, 0], aircraft.path[-1, 0], 0.05):
        crossed |= inside_clouds(valley, sample(aircraft.path, t))
    assert crossed


def test_terrain_is_deterministic(valley):
    a, _ = heightfield_mesh(valley.terrain)
    b, _ = heightfield_mesh(valley.terrain)
    np.testing.assert_array_equal(a, b)
