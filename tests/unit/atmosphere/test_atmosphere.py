"""The atmosphere (cloudcore.atmosphere) against references written here from the definitions alone: positions
as 3D vectors, the air's coefficients from Hillaire's parameters, fine uniform quadrature.

Tolerances: the transmittance table's rays are integrated with 64 samples (optical depth within 0.09% of
the exact, measured over 66 rays) and read bilinearly over 256 x 64 texels, so within 2e-3 of the exact
transmittance (measured 3.1e-4 at worst, at rays grazing the horizon); the sky-view table is bilinear over
192 x 108 directions with 24 samples a ray, so its radiance is within 3% of a 3,000-sample march (measured
1.4% at worst, toward the sun just below the horizon, 0.7% elsewhere; 2.8% in air of 100 times the aerosols,
the scene keys' limit).
"""

import dataclasses

import numpy as np
import pytest

from cloudcore.atmosphere import sky
from cloudcore.atmosphere.geometry import distance_to_boundary, distance_to_top, horizon_cosine, ray_hits_ground
from cloudcore.atmosphere.medium import ISOTROPIC_PHASE, cornette_shanks_phase, rayleigh_phase
from cloudcore.atmosphere.parameters import EARTH
from cloudcore.atmosphere.scattering import in_scattering, multiple_scattering_lookup
from cloudcore.atmosphere.sky import atmosphere_tables, sky_irradiance, sky_seen_from, sun_transmittance
from cloudcore.atmosphere.sun_disc import SUN_ANGULAR_RADIUS, disc_radiance, visible_fraction
from cloudcore.atmosphere.transmittance import optical_depth, transmittance_to_top
from cloudcore.light.lighting import PHYSICAL_EXPOSURE
from cloudcore.light.phase import phase_function
from cloudcore.light.sky_background import NIGHT_SKY, scene_sky
from cloudcore.model.scene import Lighting
from cloudcore.runtime import disk_cache

R, TOP = EARTH.bottom_radius_m, EARTH.top_radius_m


# ---- the reference: the definitions, as plainly as they can be written -------------------------------------


def air(altitude):
    """(Rayleigh scattering, Mie scattering, extinction) (..., 3) per metre, from the parameters' definitions."""
    altitude = np.asarray(altitude, dtype=np.float64)[..., None]
    rayleigh = np.exp(-altitude / EARTH.rayleigh_scale_height_m) * np.array(EARTH.rayleigh_scattering)
    mie_density = np.exp(-altitude / EARTH.mie_scale_height_m)
    ozone = np.clip(1.0 - np.abs(altitude - 25_000.0) / 15_000.0, 0.0, None) * np.array(EARTH.ozone_absorption)
    extinction = rayleigh + mie_density * np.array(EARTH.mie_extinction) + ozone
    return rayleigh, mie_density * np.array(EARTH.mie_scattering), extinction


def sphere_exit(points, direction, radius):
    """How far from `points` (..., 3) along `direction` (3,) the sphere of `radius` is met going out."""
    b = points @ direction
    c = np.einsum("...i,...i", points, points) - radius**2
    return -b + np.sqrt(np.maximum(b * b - c, 0.0))


def ground_hit(points, direction):
    """How far from `points` along `direction` the ground is met, inf where it is not."""
    b = points @ direction
    disc = b * b - (np.einsum("...i,...i", points, points) - R**2)
    return np.where((disc >= 0) & (b < 0), -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)


def exact_depth(point, direction, length, samples=200_001):
    """The optical depth (3,) from `point` over `length` along `direction`: the trapezoid rule on fine steps."""
    t = np.linspace(0.0, length, samples)
    altitude = np.linalg.norm(point + t[:, None] * direction, axis=1) - R
    return np.trapezoid(air(altitude)[2], t, axis=0)


def sun_transmittances(points, sun, samples=800):
    """(..., 3): the transmittance from `points` toward the sun to the top, 0 where the ground hides it."""
    exit_distance = sphere_exit(points, sun, TOP)
    s = (np.arange(samples) + 0.5) / samples
    along = points[..., None, :] + (exit_distance[..., None, None] * s[:, None]) * sun
    extinction = air(np.linalg.norm(along, axis=-1) - R)[2]
    depth = extinction.sum(axis=-2) * (exit_distance / samples)[..., None]
    return np.exp(-depth) * ~np.isfinite(ground_hit(points, sun))[..., None]


def reference_sky(direction, sun, samples=3000):
    """The sky's radiance (3,) from the ground along `direction`: the sun's single scattering by a fine march
    (its transmittances marched too), plus the higher orders through the model's psi_ms table."""
    eye = np.array([0.0, R, 0.0])
    length = min(sphere_exit(eye, direction, TOP), ground_hit(eye, direction))
    dt = length / samples
    points = eye + ((np.arange(samples) + 0.5) * dt)[:, None] * direction
    radius = np.linalg.norm(points, axis=1)
    rayleigh, mie, extinction = air(radius - R)
    to_eye = np.exp(-(np.cumsum(extinction, axis=0) - 0.5 * extinction) * dt)
    nu = direction @ sun
    g = EARTH.mie_g
    rayleigh_phase_here = 3.0 / (16.0 * np.pi) * (1.0 + nu * nu)
    mie_phase_here = 3.0 / (8.0 * np.pi) * (1 - g * g) / (2 + g * g) * (1 + nu * nu) / (1 + g * g - 2 * g * nu) ** 1.5
    lit = sun_transmittances(points, sun)
    single = (to_eye * lit * (rayleigh * rayleigh_phase_here + mie * mie_phase_here)).sum(axis=0) * dt
    psi = multiple_scattering_lookup(EARTH, atmosphere_tables(EARTH).multiple_scattering, radius, points @ sun / radius)
    return single + (to_eye * psi * (rayleigh + mie)).sum(axis=0) * dt


def toward(elevation_deg, azimuth_deg=0.0):
    """The unit direction at `elevation_deg` above the horizon, `azimuth_deg` from +z toward +x."""
    e, a = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.array([np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)])


# ---- the medium and the geometry ----------------------------------------------------------------------------


def test_the_phase_functions_are_normalised_and_those_of_the_clouds_divided_by_4_pi():
    mu = np.linspace(-1.0, 1.0, 200_001)
    assert 2 * np.pi * np.trapezoid(rayleigh_phase(mu), mu) == pytest.approx(1.0, rel=1e-9)
    assert 2 * np.pi * np.trapezoid(cornette_shanks_phase(mu, 0.8), mu) == pytest.approx(1.0, rel=1e-4)
    np.testing.assert_allclose(4 * np.pi * rayleigh_phase(mu), phase_function(mu, "rayleigh"))
    np.testing.assert_allclose(4 * np.pi * cornette_shanks_phase(mu, 0.8), phase_function(mu, "cornette-shanks", 0.8))
    assert 4 * np.pi * ISOTROPIC_PHASE == pytest.approx(1.0)


def test_ray_geometry_straight_up_grazing_and_down():
    assert distance_to_top(R, 1.0, TOP) == pytest.approx(TOP - R)
    grazing = np.sqrt(TOP**2 - R**2)
    assert distance_to_top(R, 0.0, TOP) == pytest.approx(grazing)
    assert distance_to_boundary(R + 1000.0, -1.0, R, TOP) == pytest.approx(1000.0)
    assert ray_hits_ground(R + 1000.0, -0.5, R) and not ray_hits_ground(R + 1000.0, 0.0, R)
    # the horizon's ray just touches the ground: grazing it, a hair above and below, nothing turns NaN
    horizon = horizon_cosine(R + 1000.0, R)
    assert horizon == pytest.approx(-np.sqrt(1 - (R / (R + 1000.0)) ** 2))
    for mu in (horizon - 1e-12, horizon, horizon + 1e-12):
        assert np.isfinite(distance_to_boundary(R + 1000.0, mu, R, TOP))


# ---- transmittance ------------------------------------------------------------------------------------------


RAYS = [(0.0, 1.0), (0.0, 0.3), (0.0, 0.02), (0.0, 0.0), (1000.0, -0.01), (14_000.0, 0.05), (50_000.0, -0.1)]


@pytest.mark.parametrize(("altitude", "mu"), RAYS)
def test_the_transmittance_to_the_top_is_the_exponential_of_the_optical_depth(altitude, mu):
    r = R + altitude
    mu = max(mu, float(horizon_cosine(r, R)))  # the table holds rays that do not meet the ground
    point = np.array([0.0, r, 0.0])
    direction = np.array([np.sqrt(1 - mu * mu), mu, 0.0])
    length = sphere_exit(point, direction, TOP)
    exact = exact_depth(point, direction, length)
    np.testing.assert_allclose(optical_depth(EARTH, r, mu, distance_to_top(r, mu, TOP)), exact, rtol=3e-3)
    table = atmosphere_tables(EARTH).transmittance
    np.testing.assert_allclose(transmittance_to_top(EARTH, table, r, mu), np.exp(-exact), atol=2e-3)


def test_the_transmittance_of_a_segment_is_the_exponential_of_its_optical_depth():
    """What aerial perspective will ask: between the eye and a point 20 km away, low over the ground."""
    tables = atmosphere_tables(EARTH)
    r, mu, distance = R + 300.0, 0.03, 20_000.0
    _, transmittance = in_scattering(
        EARTH, tables.transmittance, tables.multiple_scattering, r, mu, 0.5, 0.2, distance, samples=20
    )
    direction = np.array([np.sqrt(1 - mu * mu), mu, 0.0])
    np.testing.assert_allclose(
        transmittance, np.exp(-exact_depth(np.array([0.0, r, 0.0]), direction, distance)), rtol=1e-3
    )


# ---- the sky ------------------------------------------------------------------------------------------------


VIEWS = {
    "zenith": toward(90.0),
    "side, 10 degrees up": toward(10.0, 90.0),
    "away from the sun, 30 up": toward(30.0, 180.0),
    "25 degrees above the sun": None,  # set per elevation
    "horizon toward the sun": toward(1.15, 11.3),
}


@pytest.mark.parametrize("sun_elevation", [60.0, 20.0, 5.0, -2.0])
def test_the_sky_s_radiance_is_a_fine_march_s(sun_elevation):
    sun = toward(sun_elevation)
    view = sky_seen_from(EARTH, 0.0, sun)
    for name, direction in VIEWS.items():
        direction = toward(sun_elevation + 25.0) if direction is None else direction
        expected = reference_sky(direction, sun)
        assert (expected > 0).all()
        np.testing.assert_allclose(view.radiance(direction), expected, rtol=0.03, err_msg=name)


def test_at_sunset_the_zenith_is_blue_and_the_horizon_toward_the_sun_red():
    setting = sky_seen_from(EARTH, 0.0, toward(2.0))
    zenith, horizon = setting.radiance(toward(90.0)), setting.radiance(toward(2.0, 5.0))
    assert zenith[2] > zenith[0] and horizon[0] > 2 * horizon[2]
    noon_horizon = sky_seen_from(EARTH, 0.0, toward(60.0)).radiance(toward(2.0, 5.0))
    assert horizon[0] / horizon[2] > 3 * noon_horizon[0] / noon_horizon[2]


def test_the_sun_reddens_and_dims_as_it_sets_and_is_gone_below_the_horizon():
    tables = atmosphere_tables(EARTH)
    high, low, setting = (sun_transmittance(tables, 0.0, toward(e)) for e in (60.0, 5.0, 0.0))
    assert (high > low).all() and (low > setting).all()
    assert low[0] / low[2] > 3 * high[0] / high[2]
    assert sun_transmittance(tables, 0.0, toward(-np.degrees(SUN_ANGULAR_RADIUS) - 0.01)).max() == 0.0
    # half the disc above the horizon, half the light of the grazing ray
    grazing = transmittance_to_top(EARTH, tables.transmittance, R, 0.0)
    np.testing.assert_allclose(setting, 0.5 * grazing, rtol=1e-9)


def test_the_disc_above_the_horizon_is_the_area_of_a_circle_above_a_chord():
    assert visible_fraction(np.sin(SUN_ANGULAR_RADIUS), 0.0) == pytest.approx(1.0)
    assert visible_fraction(0.0, 0.0) == pytest.approx(0.5)
    # by counting points on the disc a quarter of a radius above the horizon
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-1, 1, (2, 400_000))
    inside = x * x + y * y <= 1
    counted = np.mean(y[inside] > -0.25)
    assert visible_fraction(np.sin(0.25 * SUN_ANGULAR_RADIUS), 0.0) == pytest.approx(counted, abs=3e-3)


def test_the_disc_s_radiance_integrates_to_its_irradiance():
    angle = np.linspace(0.0, 2 * SUN_ANGULAR_RADIUS, 100_001)
    irradiance = np.trapezoid(disc_radiance(angle, 1e-9) * 2 * np.pi * np.sin(angle), angle)
    assert irradiance == pytest.approx(1.0, rel=1e-3)
    assert disc_radiance(0.0, 1e-9) > disc_radiance(0.95 * SUN_ANGULAR_RADIUS, 1e-9)  # darker limb


def test_the_sky_s_irradiance_is_its_radiance_over_the_hemisphere():
    view = sky_seen_from(EARTH, 0.0, toward(40.0))
    rng = np.random.default_rng(5)
    mu, azimuth = rng.uniform(0, 1, 200_000), rng.uniform(0, 2 * np.pi, 200_000)
    sine = np.sqrt(1 - mu * mu)
    directions = np.stack([sine * np.cos(azimuth), mu, sine * np.sin(azimuth)], axis=1)
    monte_carlo = 2 * np.pi * np.mean(view.radiance(directions) * mu[:, None], axis=0)
    np.testing.assert_allclose(sky_irradiance(view.tables, 0.0, toward(40.0)), monte_carlo, rtol=0.01)
    uniform_sky = 1.0  # a sky of radiance 1 gives pi
    assert np.pi * uniform_sky == pytest.approx(2 * np.pi * np.mean(mu) * uniform_sky, rel=1e-2)


def test_the_preview_s_coarse_table_is_the_sky_within_a_few_per_cent():
    sun = toward(20.0)
    full, preview = sky_seen_from(EARTH, 0.0, sun), sky_seen_from(EARTH, 0.0, sun, preview=True)
    assert preview.table.shape == (36, 48, 3) and full.table.shape == (108, 192, 3)
    rng = np.random.default_rng(2)
    directions = rng.normal(size=(20_000, 3))
    directions[:, 1] = np.abs(directions[:, 1])
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    error = np.abs(preview.radiance(directions) / full.radiance(directions) - 1)
    assert np.median(error) < 0.01 and np.quantile(error, 0.99) < 0.03  # measured 0.6% and 2.3%


def test_multiple_scattering_brightens_the_sky_but_less_than_the_sun_s_own_light():
    tables = atmosphere_tables(EARTH)
    psi = tables.multiple_scattering
    assert (psi >= 0).all() and psi.max() < ISOTROPIC_PHASE
    # higher orders grow with the sun: psi_ms under a high sun is above that under a low one, on the ground
    assert (multiple_scattering_lookup(EARTH, psi, R, 0.9) > multiple_scattering_lookup(EARTH, psi, R, 0.1)).all()


# ---- the extremes -------------------------------------------------------------------------------------------


def test_no_nan_or_inf_at_the_extremes():
    directions = np.array(
        [[0, 1, 0], [0, -1, 0], [1, 0, 0], [0, 1e-9, 1], [0, -1e-9, 1], [0.6, 0.8, 0], [0, 0, -1]], dtype=float
    )
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    altitudes = (-500.0, 0.0, 1e-6, 8_848.0, TOP - R - 1.0, TOP - R, TOP - R + 1e5)
    suns = (toward(90.0), toward(0.0), toward(1e-7), toward(-1e-7), toward(-90.0), toward(45.0, 90.0))
    # every altitude under a sun on the horizon, every sun from the ground and from the top of the air
    cases = [(a, toward(1e-7)) for a in altitudes] + [(a, s) for a in (0.0, TOP - R) for s in suns]
    for altitude, sun in cases:
        view = sky_seen_from(EARTH, altitude, sun)
        assert np.isfinite(view.table).all() and (view.table >= 0).all()
        radiance = view.radiance(np.concatenate([directions, sun[None]]))
        assert np.isfinite(radiance).all() and (radiance >= 0).all()
        assert np.isfinite(sky_irradiance(view.tables, altitude, sun)).all()
        lit = sun_transmittance(view.tables, altitude, sun)
        assert np.isfinite(lit).all() and ((lit >= 0) & (lit <= 1)).all()


def test_turbid_air_is_hazier_and_a_dark_ground_darkens_the_sky_from_below():
    sun = toward(30.0)
    clear = sky_seen_from(EARTH, 0.0, sun)
    hazy = sky_seen_from(EARTH.with_air(mie_density_scale=5.0, ground_albedo=0.3), 0.0, sun)
    # haze whitens the sky near the horizon and dims the sun
    near_horizon = toward(5.0, 90.0)
    ratio = lambda c: c[2] / c[0]  # noqa: E731
    assert ratio(hazy.radiance(near_horizon)) < ratio(clear.radiance(near_horizon))
    assert (sun_transmittance(hazy.tables, 0.0, sun) < sun_transmittance(clear.tables, 0.0, sun)).all()
    dark = sky_seen_from(EARTH.with_air(mie_density_scale=1.0, ground_albedo=0.0), 0.0, sun)
    assert (sky_irradiance(dark.tables, 0.0, sun) < sky_irradiance(clear.tables, 0.0, sun)).all()


# ---- the cache ----------------------------------------------------------------------------------------------


def test_the_cache_key_names_every_parameter():
    base = sky.cache_key(EARTH)
    for field in dataclasses.fields(EARTH):
        value = getattr(EARTH, field.name)
        changed = tuple(v * 1.01 for v in value) if isinstance(value, tuple) else value * 1.01
        assert sky.cache_key(dataclasses.replace(EARTH, **{field.name: changed})) != base, field.name


def test_the_default_air_s_tables_ship_with_the_package_and_are_what_a_build_gives():
    shipped = disk_cache._read(
        disk_cache.entry_path(sky.CACHE_KIND, sky.cache_key(EARTH), disk_cache.shipped_directory()),
        sky.cache_key(EARTH),
    )
    assert shipped is not None, "run scripts/make_cache_entries.py"
    built = sky.build_tables(EARTH)
    for name, table in built.items():
        np.testing.assert_allclose(shipped[name], table, rtol=1e-12, err_msg=name)


def test_other_air_is_built_once_and_then_read_from_the_user_s_cache(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    params = EARTH.with_air(mie_density_scale=2.0, ground_albedo=0.1)
    sky.atmosphere_tables.cache_clear()
    first = sky.atmosphere_tables(params)
    sky.atmosphere_tables.cache_clear()
    second = sky.atmosphere_tables(params)
    assert not first.cached and second.cached and first.build_s > 0
    np.testing.assert_array_equal(first.multiple_scattering, second.multiple_scattering)


def test_below_the_horizon_a_sky_without_a_terrain_is_the_air_at_the_horizon():
    """Without a terrain (no far ground: test_far_ground.py) a ray below the horizon is drawn as the air just over
    the horizon at the same azimuth, not the table's air in front of a ground it leaves out."""
    background = scene_sky(Lighting(time_of_day=12.0))
    level = np.array([[0.6, 0.0, -0.8]])
    down = np.array([[0.6 * np.cos(0.2), -np.sin(0.2), -0.8 * np.cos(0.2)]])
    below, at_horizon = background.radiance(down, 1e-3), background.radiance(level, 1e-3)
    np.testing.assert_allclose(below, at_horizon, rtol=0.02)
    ground = np.pi * PHYSICAL_EXPOSURE * background.view.radiance(down) + NIGHT_SKY
    assert np.max(np.abs(ground - below) / below) > 0.1  # the table's air to the ground is not what is drawn
    straight_down = background.radiance(np.array([[0.0, -1.0, 0.0]]), 1e-3)
    assert np.all(np.isfinite(straight_down)) and np.all(straight_down > 0.0)
