"""The shading contract of cloudcore.light.shading.incident_light (issue: Foundation)."""

import numpy as np
import pytest

from cloudcore.light import shading
from cloudcore.light.phase import phase_function
from cloudcore.light.shading import eye_pass_coefficients, incident_light, scattering_coefficient
from cloudcore.maths.splat_kernel import splat_kernel
from tests.oracle import literal_incident_light

RNG = np.random.default_rng(20021)


def random_cloud(n=300, seed=0):
    rng = np.random.default_rng(seed)
    positions = rng.normal(size=(n, 3)) * [3.0, 1.5, 3.0]
    return positions, rng.uniform(0.5, 1.3, n)


@pytest.mark.parametrize("light", [[0.3, 0.9, 0.2], [0, 1, 0], [1, 0, 0], [0, 0, -1], [-0.5, -0.5, 0.7]])
@pytest.mark.parametrize("phase, g", [("rayleigh", 0.0), ("henyey-greenstein", 0.6), ("cornette-shanks", 0.3)])
def test_exact_matches_the_literal_algorithm(light, phase, g):
    positions, radii = random_cloud()
    tau = RNG.uniform(0.5, 6.0, len(radii))
    albedo = RNG.uniform(0.5, 1.0, len(radii))
    expected = literal_incident_light(positions, radii, tau, albedo, light, phase, g)
    got = incident_light(positions, radii, tau, albedo, light, phase=phase, g=g)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-300)


def chain(count):
    """Particles on one line along the light (+y), nearest the light first."""
    positions = np.zeros((count, 3))
    positions[:, 1] = -np.arange(count, dtype=float)
    return positions


@pytest.mark.parametrize("tau", [1e-12, 1e-3, 0.5, 2.0, 8.0, 9.0])
def test_chain_reproduces_the_literal_recurrence_where_stable(tau):
    # I_k = g_{k-1} + T_{k-1} I_{k-1} with g = sigma I, T = exp(-tau): Harris eq. 4
    sigma = 0.9 * tau * 1.5 / (4 * np.pi)
    assert sigma <= 1 - np.exp(-tau)  # the stable regime
    expected = [1.0]
    for _ in range(39):
        expected.append(sigma * expected[-1] + np.exp(-tau) * expected[-1])
    got = incident_light(chain(40), 1.0, tau, 0.9, [0, 1, 0])
    np.testing.assert_allclose(got, expected, rtol=1e-9)
    np.testing.assert_allclose(
        got, literal_incident_light(chain(40), 1.0, tau, 0.9, [0, 1, 0], stable=False), rtol=1e-9
    )


@pytest.mark.parametrize("tau", [1e-12, 1e-6, 1e-2, 1.0, 8.0, 9.3, 9.4, 50.0, 1e3, 1e6])
@pytest.mark.parametrize("albedo", [0.0, 0.9, 1.0])
def test_chain_is_finite_bounded_and_non_increasing_for_any_tau(tau, albedo):
    got = incident_light(chain(60), 1.0, tau, albedo, [0, 1, 0])
    assert np.all(np.isfinite(got))
    assert np.all((got >= 0) & (got <= 1))
    assert np.all(np.diff(got) <= 0)


def test_literal_recurrence_creates_light_where_the_cap_applies():
    # the reason for the cap: at tau = 50 the printed recurrence grows without bound
    literal = literal_incident_light(chain(10), 1.0, 50.0, 0.9, [0, 1, 0], stable=False)
    assert literal[-1] > 1e6
    assert incident_light(chain(10), 1.0, 50.0, 0.9, [0, 1, 0])[-1] <= 1.0


def test_result_is_continuous_in_tau_across_the_cap():
    taus = np.linspace(5.0, 15.0, 2001)
    last = np.array([incident_light(chain(8), 1.0, t, 0.9, [0, 1, 0])[-1] for t in taus])
    assert np.max(np.abs(np.diff(last))) < 5e-3  # steps shrink with the tau spacing: no jump


def test_cap_equals_the_paper_where_sigma_does_not_exceed_alpha():
    tau = np.linspace(0, 9.2, 50)
    np.testing.assert_allclose(scattering_coefficient(tau, 0.9) * 1.5, 0.9 * tau * 1.5 / (4 * np.pi))
    big = np.array([10.0, 1e3, 1e6])
    np.testing.assert_allclose(scattering_coefficient(big, 0.9) * 1.5, 1 - np.exp(-big))


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1e3, 1e6])
def test_extreme_radii_give_the_same_shading_as_unit_scale(scale):
    positions, radii = random_cloud(200, seed=3)
    reference = incident_light(positions, radii, 8.0, 0.9, [0.2, 1, 0.1])
    scaled = incident_light(positions * scale, radii * scale, 8.0, 0.9, [0.2, 1, 0.1])
    np.testing.assert_allclose(scaled, reference, rtol=1e-9)


def test_coincident_particles_shade_in_index_order():
    positions = np.ones((1000, 3)) * 123.0
    got = incident_light(positions, 2.0, 0.3, 0.9, [0, 1, 0])
    a, s = 1 - np.exp(-0.3), 0.9 * 0.3 * 1.5 / (4 * np.pi)
    np.testing.assert_allclose(got, (1 - a + s) ** np.arange(1000), rtol=1e-9)


def test_empty_and_single_particle():
    assert incident_light(np.zeros((0, 3)), [], [], [], [0, 1, 0]).shape == (0,)
    assert incident_light([[1.0, 2.0, 3.0]], [5.0], [8.0], [0.9], [0, 1, 0]).tolist() == [1.0]


def test_albedo_zero_is_pure_attenuation():
    positions = chain(5)
    got = incident_light(positions, 1.0, 2.0, 0.0, [0, 1, 0])
    np.testing.assert_allclose(got, np.exp(-2.0 * np.arange(5)), rtol=1e-12)


def test_particles_out_of_each_others_splats_are_fully_lit():
    positions = np.array([[0, 0, 0], [5, -1, 0], [0, -1, 5]], float)
    np.testing.assert_array_equal(incident_light(positions, 1.0, 8.0, 0.9, [0, 1, 0]), 1.0)


def test_groups_shade_independently():
    a, ra = random_cloud(150, seed=1)
    b, rb = random_cloud(120, seed=2)
    together = incident_light(
        np.vstack([a, b]), np.concatenate([ra, rb]), 8.0, 0.9, [0, 1, 0], groups=np.repeat([0, 1], [150, 120])
    )
    np.testing.assert_allclose(together[:150], incident_light(a, ra, 8.0, 0.9, [0, 1, 0]), rtol=1e-12)
    np.testing.assert_allclose(together[150:], incident_light(b, rb, 8.0, 0.9, [0, 1, 0]), rtol=1e-12)


def test_mixed_radii_use_the_banded_search_and_stay_exact():
    positions, radii = random_cloud(250, seed=5)
    radii = radii * np.where(np.arange(250) % 7 == 0, 20.0, 1.0)
    expected = literal_incident_light(positions, radii, 4.0, 0.9, [0.1, 1, 0.3])
    np.testing.assert_allclose(incident_light(positions, radii, 4.0, 0.9, [0.1, 1, 0.3]), expected, rtol=1e-9)


@pytest.mark.parametrize("method, mean_error", [("raster", 0.03), ("preview", 0.07)])
def test_raster_mode_is_close_to_exact_and_bounded(method, mean_error):
    """The raster and the editor's preview (a coarser grid, thicker slabs: 0.024 and 0.063 here; the preview's
    slabs of 0.05 radii gave 0.057, of 0.5 radii 0.118)."""
    positions, radii = random_cloud(1500, seed=7)
    exact = incident_light(positions, radii, 8.0, 0.9, [0.3, 0.9, 0.2])
    raster = incident_light(positions, radii, 8.0, 0.9, [0.3, 0.9, 0.2], method=method)
    assert np.all((raster >= 0) & (raster <= 1))
    assert np.mean(np.abs(raster - exact)) < mean_error


def test_a_footprint_is_every_cell_whose_centre_the_splat_covers_with_its_kernel_weight():
    rng = np.random.default_rng(3)
    resolution = 12
    centre = rng.uniform(-2.0, resolution + 2.0, (400, 2))
    radius = np.concatenate([rng.uniform(0.0, 3.0, 398), [0.0, 40.0]])  # none, and wider than the grid
    cells, weight, owner = shading._footprints(centre, radius, resolution)
    x, y = np.meshgrid(np.arange(resolution) + 0.5, np.arange(resolution) + 0.5)
    for splat in range(len(centre)):
        with np.errstate(divide="ignore", invalid="ignore"):
            d = (np.hypot(x - centre[splat, 0], y - centre[splat, 1]) / radius[splat]).ravel()
        expected = np.flatnonzero(splat_kernel(d) > 0)
        mine = owner == splat
        np.testing.assert_array_equal(cells[mine], expected)
        np.testing.assert_array_equal(weight[mine], splat_kernel(d[expected]))


@pytest.mark.parametrize("tau", [0.0, 1e-12, 1e6])
def test_raster_mode_is_finite_at_the_extremes(tau):
    positions, radii = random_cloud(300, seed=9)
    got = incident_light(positions, radii, tau, 0.9, [0, 1, 0], method="raster")
    assert np.all(np.isfinite(got)) and np.all((got >= 0) & (got <= 1))


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(positions=[[np.nan, 0, 0]]), "positions must be finite"),
        (dict(positions=[[np.inf, 0, 0]]), "positions must be finite"),
        (dict(radii=[-1.0]), "radii must be >= 0"),
        (dict(optical_depth=[-0.1]), "optical_depth must be >= 0"),
        (dict(optical_depth=[np.nan]), "optical_depth must be finite"),
        (dict(albedo=[1.5]), "albedo"),
        (dict(light_dir=[0, 0, 0]), "zero vector"),
        (dict(light_dir=[0, np.nan, 1]), "light_dir"),
        (dict(positions=[[0, 0]]), r"shape \(N, 3\)"),
        (dict(radii=[1.0, 2.0]), "radii must have shape"),
    ],
)
def test_bad_input_raises_value_error_with_a_message(change, message):
    arguments = dict(positions=[[0.0, 0.0, 0.0]], radii=[1.0], optical_depth=[8.0], albedo=[0.9], light_dir=[0, 1, 0])
    arguments.update(change)
    with pytest.raises(ValueError, match=message):
        incident_light(**arguments)


def test_unknown_method_is_refused():
    with pytest.raises(ValueError, match="exact, raster"):
        incident_light([[0, 0, 0]], [1], [1], [1], [0, 1, 0], method="magic")


def test_the_saturated_eye_pass_is_harris_s_for_thin_particles_and_bounded_for_thick_ones():
    thin, thick = np.array([1e-4]), np.array([8.0])
    for tau in (thin, thick):
        harris = eye_pass_coefficients(tau, 0.9, eye_pass="harris")
        assert harris[0] == pytest.approx(scattering_coefficient(tau, 0.9)) and harris[1] == pytest.approx(
            -np.expm1(-tau)
        )
    scattering, ambient = eye_pass_coefficients(thin, 0.9, eye_pass="saturated")
    assert scattering == pytest.approx(0.9 * thin / (4 * np.pi), rel=1e-3)
    scattering, ambient = eye_pass_coefficients(thick, 0.9, eye_pass="saturated")
    assert scattering == pytest.approx(0.9 / (4 * np.pi), rel=1e-3)  # Harris: 0.57, eight times this
    s = np.sqrt(0.1)
    assert ambient == pytest.approx((1 - s) / (1 + s), rel=1e-3)
    # at albedo 1 the ambient term is Harris's (a white cloud in uniform light returns it exactly)
    assert eye_pass_coefficients(thick, 1.0, eye_pass="saturated")[1] == pytest.approx(-np.expm1(-thick))
    # a strong forward lobe keeps Harris's cap: no more light forward than the particle stops
    forward, _ = eye_pass_coefficients(thick, 0.9, "henyey-greenstein", 0.9, eye_pass="saturated")
    assert forward * phase_function(1.0, "henyey-greenstein", 0.9) == pytest.approx(-np.expm1(-thick))
    with pytest.raises(ValueError, match="harris, saturated"):
        eye_pass_coefficients(thick, 0.9, eye_pass="magic")


def test_changing_the_eye_pass_shades_nothing_again():
    from cloudcore.light.illumination import IlluminationCache
    from cloudcore.model.scene import Cloud, Light, Shading

    cloud = Cloud("c", [[0.0, 0.0, 0.0, 10.0], [5.0, 5.0, 0.0, 10.0]])
    cache, lights = IlluminationCache(), (Light((0.0, 1.0, 0.0)),)
    cache.incident([cloud], Shading(), lights)
    cache.incident([cloud], Shading(eye_pass="saturated"), lights)
    assert cache.last_recomputed == 0
