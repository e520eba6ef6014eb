"""The tables seen from an altitude built at knots and blended between them (`cloudcore.atmosphere.sky.altitude_knots`):
which altitudes are built, the blend against the tables built at its own altitude, and what a climb builds."""

import numpy as np
import pytest

from cloudcore.atmosphere import aerial_perspective, sky_view
from cloudcore.atmosphere.aerial_perspective import aerial_perspective_from, build_aerial_perspective
from cloudcore.atmosphere.parameters import EARTH
from cloudcore.atmosphere.sky import KNOT_STEP_M, KNOTS_FROM_M, altitude_knots, atmosphere_tables, sky_seen_from
from cloudcore.world.sun import sun_direction

TABLES = atmosphere_tables(EARTH)


@pytest.mark.parametrize(
    ("altitude", "knots"),
    [
        (0.0, (0.0, 0.0, 0.0)),
        (700.0, (700.0, 700.0, 0.0)),
        (KNOTS_FROM_M, (KNOTS_FROM_M, KNOTS_FROM_M, 0.0)),
        (2300.0, (2000.0, 2500.0, 0.6)),
        (2500.0, (2500.0, 2500.0, 0.0)),
    ],
)
def test_an_altitude_is_built_below_the_knots_and_at_a_knot_and_blended_between_two_above(altitude, knots):
    below, above, share = altitude_knots(altitude)
    assert (below, above) == knots[:2] and share == pytest.approx(knots[2])


def test_a_blend_between_knots_strays_from_the_tables_built_at_its_altitude_less_than_a_100_m_step_changes_them():
    """At 2,250 m, midway between two knots: the sky-view table and the air's volume blended from the knots' differ
    from those built at 2,250 m by less than the tables of two neighbouring 100 m steps (2,200 and 2,300 m) differ,
    which the eye climbing through the steps saw change at each, and the blend is the knots' tables mixed by the
    share."""
    sun = sun_direction(9.4)
    blended_sky = sky_seen_from(EARTH, 2250.0, sun).table
    low, high = (sky_seen_from(EARTH, knot, sun).table for knot in (2000.0, 2500.0))
    np.testing.assert_allclose(blended_sky, 0.5 * low + 0.5 * high, rtol=1e-12)
    exact, step_below, step_above = (
        sky_view.build_sky_view_table(EARTH, TABLES.transmittance, TABLES.multiple_scattering, altitude, sun[1])[0]
        for altitude in (2250.0, 2200.0, 2300.0)
    )
    assert np.abs(blended_sky - exact).max() < np.abs(step_above - step_below).max()
    volume = aerial_perspective_from(TABLES, 2250.0, sun)
    exact, step_below, step_above = (build_aerial_perspective(TABLES, a, sun) for a in (2250.0, 2200.0, 2300.0))
    for name in ("in_scattered", "transmittance"):
        blend_error = np.abs(getattr(volume, name) - getattr(exact, name)).max()
        assert blend_error < np.abs(getattr(step_above, name) - getattr(step_below, name)).max()


def test_a_climb_builds_the_knots_tables_alone(monkeypatch):
    """An eye climbing from 2,000 to 4,200 m in 100 m steps (the cumulus field's flight) builds the volume and the
    sky-view table at the 6 knots it passes, not at its 23 steps."""
    volumes, skies = [], []
    build_volume, build_sky = aerial_perspective.build_aerial_perspective, sky_view.build_sky_view_table
    monkeypatch.setattr(
        aerial_perspective, "build_aerial_perspective", lambda *args: volumes.append(args[1]) or build_volume(*args)
    )
    monkeypatch.setattr(sky_view, "build_sky_view_table", lambda *args: skies.append(args[3]) or build_sky(*args))
    sun = sun_direction(8.15)  # an hour no other test draws, so that no table of it is cached
    for altitude in np.arange(2000.0, 4201.0, 100.0):
        aerial_perspective_from(TABLES, altitude, sun)
        assert np.isfinite(sky_seen_from(EARTH, altitude, sun).table).all()
    knots = list(np.arange(2000.0, 4501.0, KNOT_STEP_M))
    assert volumes == knots and skies == knots
