"""Yusov's precomputed reference particle: its tables' limits and symmetries, the disk cache, and the
light-space occlusion estimate against Harris's exact light pass."""

import numpy as np
import pytest
from scipy.integrate import quad

from cloudcore.light import precomputed
from cloudcore.light.illumination import illuminate_direction
from cloudcore.light.occlusion import occlusion_estimate
from cloudcore.light.phase import phase_function
from cloudcore.light.precomputed import (
    TableResolution,
    chord_depths,
    chord_optical_depth,
    eye_pass_profiles,
    reference_tables,
)
from cloudcore.light.shading import eye_pass_coefficients, incident_light
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, splat_kernel
from cloudcore.model.scene import Cloud, Light, Scene, Shading
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.resources import resource_path
from cloudcore.runtime import disk_cache
from cloudcore.scenes.files import load_scene, save_scene

#: small enough to build in about a second: for the tests of the cache, not of accuracy
TINY = TableResolution(
    chord_impacts=17,
    chord_positions=17,
    view_cosines=9,
    log2_tau_low=-1,
    log2_tau_high=2,
    volume_radii=8,
    volume_polar=8,
    volume_azimuths=8,
    voxels=8,
    direction_cosines=4,
    direction_azimuths=6,
    leaving_azimuths=2,
    orders=6,
)


def test_the_optical_depth_through_the_centre_is_the_particle_s_tau_and_a_chord_the_kernel_s_integral():
    table = chord_depths()
    up = np.array([0.0, 0.0, 1.0])
    assert chord_optical_depth(table, [[0.0, 0.0, -2.0]], up)[0] == pytest.approx(1.0, abs=1e-12)
    for b in (0.0, 0.3, 0.7, 0.95):
        exact = quad(lambda s, b=b: float(splat_kernel(np.hypot(b, s))), -1.0, 1.0)[0] / KERNEL_DIAMETER_INTEGRAL
        # bilinear in b: within 0.2%, or 1e-4 of the centre's near the edge where the kernel vanishes
        assert chord_optical_depth(table, [[b, 0.0, -3.0]], up)[0] == pytest.approx(exact, rel=2e-3, abs=1e-4)
    # from inside, the two ways out add up to the whole chord; behind a particle or beside it, nothing
    rng = np.random.default_rng(1)
    inside = rng.uniform(-0.55, 0.55, (200, 3))
    forward = chord_optical_depth(table, inside, up) + chord_optical_depth(table, inside, -up)
    whole = chord_optical_depth(table, inside * [1.0, 1.0, 0.0] - [0.0, 0.0, 3.0], up)
    np.testing.assert_allclose(forward, whole, atol=2e-3)
    assert chord_optical_depth(table, [[0.0, 0.0, 1.5], [1.2, 0.0, 0.0]], up).tolist() == [0.0, 0.0]


def test_a_thin_particle_scatters_as_harris_s_eye_pass_and_nothing_more():
    """tau -> 0: single scattering -> albedo tau p / (4 pi) (with the splat's opacity alpha), no orders."""
    tau, albedo = 1e-4, 0.8
    profiles = eye_pass_profiles([tau], [albedo])
    mu = np.linspace(-1.0, 1.0, 7)
    single, multiple = profiles.at(np.zeros(7, dtype=np.int64), mu)
    alpha = -np.expm1(-tau)
    np.testing.assert_allclose(
        alpha * single * phase_function(mu), albedo * tau * phase_function(mu) / (4 * np.pi), rtol=2e-4
    )
    assert np.all(alpha * multiple < 1e-3 * alpha * single)
    scattering, ambient = eye_pass_coefficients([tau], [albedo], eye_pass="yusov")
    assert scattering[0] == pytest.approx(alpha) and ambient[0] == pytest.approx(albedo * tau, rel=1e-3)


def test_a_white_particle_returns_the_uniform_light_it_occludes():
    """In uniform light of radiance 1 a non-absorbing particle sends out all it stops: the ambient response is
    1 at every tau (the check on every scattering order and the tail at once), less at albedo 0.9."""
    tables = reference_tables()
    taus = tables.optical_depths
    _, _, white = tables.scattering_profiles(taus, np.ones(len(taus)))
    np.testing.assert_allclose(white, 1.0, atol=0.025)
    _, _, grey = tables.scattering_profiles(taus, np.full(len(taus), 0.9))
    assert np.all(grey < white) and np.all(np.diff(grey) <= 1e-9)  # thicker: more orders, each losing 10%


def test_the_lit_side_is_brighter_and_thick_particles_stay_finite():
    tables = reference_tables()
    single, multiple, ambient = tables.scattering_profiles([8.0, 1e300, np.inf, 0.0], [0.9, 0.9, 1.0, 0.0])
    for values in (single, multiple, ambient):
        assert np.all(np.isfinite(values)) and np.all(values >= 0.0)
    # mu -1: the light behind the eye, the lit face seen; +1: looking through the particle at the light
    assert single[0, 0] > 1.5 * single[0, -1] and multiple[0, 0] > multiple[0, -1]
    np.testing.assert_array_equal(single[1], single[2] * 0.9)  # past the last node the particle is opaque
    assert np.all(single[3] == 0.0) and np.all(multiple[3] == 0.0)  # albedo 0 scatters nothing


def test_an_opaque_particle_with_yusov_s_eye_pass_has_finite_colours():
    clouds = (Cloud("c", np.array([[0.0, 0.0, -50.0, 5.0], [0.0, 0.0, -60.0, 1e-9]]), optical_depth=1e30),)
    particles = ParticleBuffer(
        clouds, Shading(eye_pass="yusov"), (Light((0.0, 0.0, 1.0), (1.0, 1.0, 1.0), 1.0),), (0.1, 0.1, 0.1)
    )
    colour, alpha = particles.seen_from((0.0, 0.0, 0.0), np.arange(2))
    assert np.all(np.isfinite(colour)) and np.all(alpha <= 1.0) and np.all(colour <= 1.0)


def test_the_tables_are_cached_on_disk_rebuilt_when_corrupt_or_stale(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(precomputed, "_held", {})
    built = reference_tables("henyey-greenstein", 0.5, TINY)
    assert not built.cached and built.build_s > 0
    files = list((tmp_path / "cloudview" / "reference-particle").glob("*.npz"))
    assert len(files) == 1

    monkeypatch.setattr(precomputed, "_held", {})
    again = reference_tables("henyey-greenstein", 0.5, TINY)
    assert again.cached
    np.testing.assert_array_equal(again.orders, built.orders)
    assert again.nbytes == built.nbytes

    files[0].write_bytes(b"not a zip file")  # a crash mid-write elsewhere, a full disc, a bad sector
    monkeypatch.setattr(precomputed, "_held", {})
    rebuilt = reference_tables("henyey-greenstein", 0.5, TINY)
    assert not rebuilt.cached
    np.testing.assert_array_equal(rebuilt.single, built.single)

    monkeypatch.setattr(precomputed, "FORMAT_VERSION", precomputed.FORMAT_VERSION + 1)
    monkeypatch.setattr(precomputed, "_held", {})
    assert not reference_tables("henyey-greenstein", 0.5, TINY).cached  # another format: another entry
    assert len(list(files[0].parent.glob("*.npz"))) == 2


def test_a_cache_entry_under_another_key_is_a_miss(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    first, second = {"format": 1, "what": "a"}, {"format": 1, "what": "b"}
    assert not disk_cache.load_or_build("kind", first, lambda: {"x": np.arange(3.0)})[1]
    # the second key's file holding the first key's arrays (a hash collision, a file copied by hand)
    disk_cache.entry_path("kind", second).write_bytes(disk_cache.entry_path("kind", first).read_bytes())
    arrays, cached = disk_cache.load_or_build("kind", second, lambda: {"x": np.zeros(2)})
    assert not cached and arrays["x"].tolist() == [0.0, 0.0]
    arrays, cached = disk_cache.load_or_build("kind", second, lambda: {})
    assert cached and arrays["x"].tolist() == [0.0, 0.0]


def test_the_cache_folder_follows_xdg_and_falls_back_to_the_home(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert disk_cache.cache_directory() == tmp_path / "xdg" / "cloudview"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert disk_cache.cache_directory() == tmp_path / "home" / ".cache" / "cloudview"


# ---------------------------------------------------------------- the occlusion estimate


@pytest.mark.parametrize("tau", [0.1, 2.0, 8.0, 60.0])
def test_one_occluder_straight_ahead_passes_what_harris_s_exact_pass_says(tau):
    """Below an occluder whose kernel does not reach the target's centre, Harris's exact light pass gives
    1 - (alpha - sigma): the estimate loses xi = 1 - sigma / alpha of alpha, the same."""
    positions = np.array([[0.0, 0.0, 0.0], [0.0, 1.5, 0.0]])
    for phase, g in (("rayleigh", 0.0), ("henyey-greenstein", 0.6)):
        exact = incident_light(positions, 1.0, tau, 0.9, [0.0, 1.0, 0.0], phase=phase, g=g, method="exact")
        estimate = incident_light(positions, 1.0, tau, 0.9, [0.0, 1.0, 0.0], phase=phase, g=g, method="occlusion")
        np.testing.assert_allclose(estimate, exact, atol=1e-9)


def test_a_thin_column_of_particles_is_lit_as_harris_s_exact_pass_lights_it():
    """Thin particles: light order no longer matters, and the estimate before smoothing is Harris's but for
    the kernel: the splat's 2D K in Harris's light plane, the blob's chord (a little wider) here."""
    rng = np.random.default_rng(3)
    positions = np.column_stack([rng.normal(0.0, 2.0, (60, 2)), rng.uniform(0.0, 40.0, 60)])[:, [0, 2, 1]]
    tau, albedo = 0.05, 0.9
    exact = incident_light(positions, 3.0, tau, albedo, [0.0, 1.0, 0.0], method="exact")
    lost = 1.0 - albedo * tau * 1.5 / (4 * np.pi) / -np.expm1(-tau)  # 1 - sigma / alpha, Rayleigh
    n = len(positions)
    estimate = occlusion_estimate(
        positions[:, [0, 2]],
        positions[:, 1],
        np.full(n, 3.0),
        np.full(n, tau),
        np.full(n, lost),
        np.zeros(n, int),
        smoothed=False,
    )
    assert exact.min() < 0.9  # the column shades itself
    np.testing.assert_allclose(estimate, exact, atol=0.03)
    assert np.abs(estimate - exact).mean() < 0.006


def test_the_estimate_keeps_groups_apart_and_its_extremes_finite():
    positions = np.array([[0.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 3.0, 0.0]])
    apart = incident_light(positions, 1.0, 4.0, 0.9, [0, 1, 0], method="occlusion", groups=[0, 1, 2])
    np.testing.assert_array_equal(apart, 1.0)
    assert incident_light(np.zeros((0, 3)), 1.0, 1.0, 0.9, [0, 1, 0], method="occlusion").shape == (0,)
    extremes = incident_light(positions, [0.0, 1.0, 1.0], [1e300, 1e300, 0.0], 1.0, [0, 1, 1], method="occlusion")
    assert np.all(np.isfinite(extremes)) and np.all((extremes >= 0.0) & (extremes <= 1.0))
    coincident = incident_light(np.zeros((3, 3)), 1.0, 8.0, 0.9, [1, 0, 0], method="occlusion")
    assert np.all(np.isfinite(coincident))


def test_the_tables_of_every_shipped_scenes_phase_function_ship_with_the_package(tmp_path, monkeypatch):
    """A fresh install reads them (`scripts/make_cache_entries.py` writes them): nothing to build for a minute."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))  # an empty user cache
    for scene_file in sorted(resource_path("scenes").glob("*.toml")):
        shading = load_scene(scene_file).shading
        g = 0.0 if shading.phase == "rayleigh" else shading.g
        arrays, cached = disk_cache.load_or_build(
            precomputed.CACHE_KIND, precomputed.cache_key(shading.phase, g), lambda: pytest.fail("built")
        )
        assert cached and arrays["single"].size, scene_file.name
    assert not list(tmp_path.rglob("*.npz"))  # and nothing was written into the user's cache


def test_a_shipped_entry_is_read_before_the_users_cache(tmp_path, monkeypatch):
    shipped, users = tmp_path / "shipped", tmp_path / "users"
    monkeypatch.setattr(disk_cache, "shipped_directory", lambda: shipped)
    monkeypatch.setenv("XDG_CACHE_HOME", str(users))
    key = {"format": 1, "what": "a"}
    disk_cache.store("kind", key, {"x": np.ones(2)}, shipped)
    disk_cache.store("kind", key, {"x": np.zeros(2)})
    arrays, cached = disk_cache.load_or_build("kind", key, lambda: pytest.fail("built"))
    assert cached and arrays["x"].tolist() == [1.0, 1.0]


def test_a_scenes_occlusion_light_pass_runs_yusovs_estimate_where_harris_exact_would(tmp_path):
    rng = np.random.default_rng(3)
    clouds = [Cloud("c", np.column_stack([rng.normal(0.0, 60.0, (80, 3)), np.full(80, 30.0)]))]
    sun = (0.3, 0.8, 0.5)
    occlusion = Shading(light_pass="occlusion")
    estimated = illuminate_direction(clouds, occlusion, sun, "exact")[0]
    np.testing.assert_array_equal(estimated, illuminate_direction(clouds, Shading(), sun, "occlusion")[0])
    assert np.abs(estimated - illuminate_direction(clouds, Shading(), sun, "exact")[0]).max() > 1e-3
    # the editor's preview while a slider moves stays Harris's fast one
    np.testing.assert_array_equal(
        illuminate_direction(clouds, occlusion, sun, "preview")[0],
        illuminate_direction(clouds, Shading(), sun, "preview")[0],
    )
    path = tmp_path / "s.toml"
    save_scene(Scene(shading=occlusion, clouds=tuple(clouds)), path)
    assert load_scene(path).shading.light_pass == "occlusion" and 'light_pass = "occlusion"' in path.read_text()
