"""Time of day to sun, skylight and sky (cloudcore.light.lighting)."""

import numpy as np
import pytest

from cloudcore.atmosphere.sky import atmosphere_tables, sky_irradiance, sun_transmittance
from cloudcore.light.lighting import (
    PHYSICAL_EXPOSURE,
    active_lights,
    atmosphere_parameters,
    daylight,
    scene_lights,
    sky_colors,
    sun_beam,
)
from cloudcore.model.scene import Air, Light, Lighting
from cloudcore.world.sun import elevation_deg, sun_direction

GRADIENT = Air(sky="gradient")


def test_sun_rises_in_the_east_peaks_south_at_noon_and_sets_in_the_west():
    hours = np.linspace(0, 24, 24 * 60 + 1)
    elevations = np.array([elevation_deg(sun_direction(h)) for h in hours])
    assert hours[np.argmax(elevations)] == pytest.approx(12.0)
    assert sun_direction(12.0)[2] > 0  # south is +z
    assert sun_direction(9.0)[0] > 0 and sun_direction(15.0)[0] < 0  # east +x in the morning
    up = hours[elevations > 0]
    assert 4.5 < up.min() < 6.0 and 18.0 < up.max() < 19.5
    assert elevation_deg(sun_direction(0.0)) < -20


@pytest.mark.parametrize("air", [Air(), GRADIENT], ids=["physical", "gradient"])
@pytest.mark.parametrize("hours", np.linspace(0, 24, 97))
def test_daylight_is_finite_and_bounded_at_every_hour(hours, air):
    brightest = PHYSICAL_EXPOSURE if air.sky == "physical" else 1.0
    lights, ambient = daylight(hours, air)
    for light in lights:
        assert np.isclose(np.linalg.norm(light.direction), 1.0)
        assert 0 <= min(light.color) and max(light.color) <= 1 and 0 <= light.intensity <= brightest
    assert np.all((ambient > 0) & (ambient < 1))
    for color in sky_colors(hours):
        assert np.all(np.isfinite(color)) and np.all((color >= 0) & (color <= 1))


@pytest.mark.parametrize("air", [Air(), GRADIENT], ids=["physical", "gradient"])
def test_sun_is_golden_low_and_gone_at_night(air):
    noon_color, _ = daylight(12.0, air)[0][0].color, None
    evening = daylight(18.3, air)[0][0]
    assert evening.color[2] / evening.color[0] < 0.6 * noon_color[2] / noon_color[0]
    night_lights, _ = daylight(0.0, air)
    assert active_lights(night_lights) == ()  # no shading pass for lights that give nothing
    assert len(active_lights(daylight(15.5, air)[0])) == 2


@pytest.mark.parametrize("hours", [6.0, 12.0, 18.25])
def test_the_physical_sky_s_lights_are_the_atmosphere_s_beam_and_irradiance_at_the_exposure(hours):
    air = Air(mie_density_scale=2.0, ground_albedo=0.2, origin_altitude_m=800.0)
    (sun, skylight), ambient = daylight(hours, air)
    params = atmosphere_parameters(air)
    beam = sun_transmittance(atmosphere_tables(params), 800.0, sun_direction(hours))
    np.testing.assert_allclose(np.array(sun.color) * sun.intensity, PHYSICAL_EXPOSURE * beam, rtol=1e-12)
    assert skylight.direction == (0.0, 1.0, 0.0)
    sky = sky_irradiance(atmosphere_tables(params), 800.0, sun_direction(hours))
    np.testing.assert_allclose(np.array(skylight.color) * skylight.intensity, PHYSICAL_EXPOSURE * sky, rtol=1e-12)
    # a brighter ground lights the clouds' undersides more
    assert (daylight(hours, Air(ground_albedo=0.8))[1] > daylight(hours, Air(ground_albedo=0.1))[1]).all()


def test_the_gradient_keeps_the_heuristic_sun_of_before():
    sun, _ = daylight(9.0, GRADIENT)[0]
    colour, intensity = sun_beam(elevation_deg(sun_direction(9.0)))
    np.testing.assert_array_equal(sun.color, colour)
    assert sun.intensity == intensity


def test_a_scene_s_air_reaches_its_lights():
    physical, _ = scene_lights(Lighting(time_of_day=17.0))
    gradient, _ = scene_lights(Lighting(time_of_day=17.0, air=GRADIENT))
    assert physical != gradient and gradient == daylight(17.0, GRADIENT)[0]


def test_sky_is_blue_by_day_and_dark_at_night():
    zenith, horizon = sky_colors(12.0)
    assert zenith[2] > zenith[0] and horizon[2] > horizon[0]
    night_zenith, _ = sky_colors(0.0)
    assert night_zenith.max() < 0.05


@pytest.mark.parametrize("hours", [-0.1, 24.1, float("nan")])
def test_time_of_day_out_of_range_is_refused(hours):
    with pytest.raises(ValueError, match="time of day"):
        sun_direction(hours)


def test_explicit_lights_replace_the_sun():
    light = Light((0.0, 1.0, 0.0), (1.0, 0.5, 0.5), 2.0)
    lights, ambient = scene_lights(Lighting(time_of_day=None, lights=(light,), ambient=(0.1, 0.2, 0.3)))
    assert lights == (light,)
    np.testing.assert_array_equal(ambient, [0.1, 0.2, 0.3])
