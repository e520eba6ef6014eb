"""Named weather over a cloud field (`cloudcore.field.weather`, `[weather]`): the presets, a change of weather whose
coverage follows its curve, and the keys refused in one line."""

import dataclasses

import numpy as np
import pytest

from cloudcore.artist.formation import formed, progress_for_share
from cloudcore.field.cells import cumulus_columns, formation_order
from cloudcore.field.state import HOLE
from cloudcore.field.weather import (
    WEATHER_PRESETS,
    preset_field,
    update_weather_field,
    weather_coverage,
    weather_shares,
)
from cloudcore.maths.ramps import smoothstep
from cloudcore.model.errors import FieldError, SceneError
from cloudcore.model.scene import WEATHER_NAMES, CloudField, Scene, Weather
from cloudcore.scenes.files import TABLE_KEYS, load_scene, save_scene
from tests.conftest import assert_file_refused_in_one_line

FIELD = CloudField(seed=4, coverage=0.1, rings=2, cloud_type="cirrus", altitude=(5000.0, 6000.0))


def test_every_named_weather_sets_the_field_s_coverage_type_and_altitudes():
    assert tuple(WEATHER_PRESETS) == WEATHER_NAMES
    cumulus_to_overcast = [WEATHER_PRESETS[name]["coverage"] for name in WEATHER_NAMES[:4]]
    assert cumulus_to_overcast == sorted(cumulus_to_overcast)
    for name in WEATHER_NAMES:
        field = preset_field(FIELD, name)
        preset = WEATHER_PRESETS[name]
        assert (field.coverage, field.cloud_type, field.altitude) == (
            preset["coverage"],
            preset["cloud_type"],
            preset["altitude"],
        )
        scale = (preset.get("cell_size", FIELD.cell_size), preset.get("layers", FIELD.layers))
        assert (field.seed, field.rings, field.cell_size, field.layers) == (FIELD.seed, FIELD.rings, *scale)
        assert weather_shares(Weather(name), 123.0) == ((name, 1.0),)
    # thunderstorms' clouds are of another scale than the field's cumulus: larger cells, every layer
    towering = preset_field(FIELD, "towering_cumulus")
    assert towering.cell_size > FIELD.cell_size and towering.layers == 8


CHANGE = Weather("scattered", to="overcast", start_s=60.0, duration_s=600.0)


def test_a_change_of_weather_s_coverage_follows_its_curve():
    times = np.linspace(0.0, 800.0, 801)
    done = smoothstep(0.0, 1.0, (times - 60.0) / 600.0)
    curve = 0.4 + (0.95 - 0.4) * done
    coverage = np.array([weather_coverage(CHANGE, t) for t in times])
    np.testing.assert_allclose(coverage, curve, atol=1e-12)
    assert coverage[0] == 0.4 and coverage[-1] == 0.95 and np.all(np.diff(coverage) >= 0.0)
    # the weather before dissipates as the one after forms, by the same smoothstep
    assert weather_shares(CHANGE, 0.0) == (("scattered", 1.0),) and weather_shares(CHANGE, 700.0) == (
        ("overcast", 1.0),
    )
    for t, s in zip(times[100:650:50], done[100:650:50]):
        (before, share_before), (after, share_after) = weather_shares(CHANGE, t)
        assert (before, after) == ("scattered", "overcast")
        assert share_before == pytest.approx(1.0 - s, abs=1e-12) and share_after == pytest.approx(s, abs=1e-12)


def test_each_weather_forms_its_share_of_its_clouds_core_first():
    """Over each weather's cloudy columns its particles' formation shows its share of their opacity, within 2%, so
    the sky's cloudy share follows the curve where the two weathers' clouds lie apart; the weather after only grows,
    and a cloud's core forms before its rim."""
    x, z = np.meshgrid(np.arange(-90000.0, 90000.0, 500.0), np.arange(-90000.0, 90000.0, 500.0))
    columns = {name: cumulus_columns(preset_field(FIELD, name), x, z)[0] for name in ("scattered", "overcast")}
    orders = {name: formation_order(preset_field(FIELD, name), x, z) for name in columns}
    earlier = None
    for t in (60.0, 150.0, 210.0, 360.0, 510.0, 600.0, 660.0):
        for name, share in weather_shares(CHANGE, t):
            opacity = formed(progress_for_share(share), orders[name])[columns[name] > 0.0]
            assert opacity.mean() == pytest.approx(share, abs=0.02)
            if name == "overcast":
                assert earlier is None or np.all(opacity >= earlier)
                earlier = opacity
    heights, order = columns["scattered"], orders["scattered"]
    cloudy = heights[heights > 0.0]
    cores = heights > np.quantile(cloudy, 0.75)  # the tallest quarter of the columns
    rims = (heights > 0.0) & (heights < np.quantile(cloudy, 0.25))
    assert np.median(order[cores]) < 0.5 * np.median(order[rims])


def test_a_change_of_weather_keeps_each_weather_s_clouds_in_their_places_and_makes_each_once():
    eye = np.array([0.0, 1500.0, 0.0])
    field = dataclasses.replace(FIELD, rings=2, cell_size=600.0)
    frame, state = update_weather_field(field, CHANGE, 0.0, eye)
    before = frame.clouds
    assert state.names == ("scattered",)
    weights, made = [], 0
    for t in np.arange(60.0, 661.0, 6.0):
        frame, state = update_weather_field(field, CHANGE, t, eye, state)
        made += sum(len(part.made) for part in state.parts)
        weights.append(frame.weights)
        if 60.0 < t < 660.0:
            assert frame.clouds[: len(before)] == before  # the weather before in its places; the one after behind
            during = frame.clouds
    assert state.names == ("overcast",) and made == len(state.in_force.cells)  # the overcast's cells made once
    # after the change, its clouds stay where they were during it: the scattered clouds' places become holes
    assert frame.clouds == (HOLE,) * state.leading + during[state.leading :]
    # no particle's weight jumps between frames a hundredth of the change apart
    for earlier, later in zip(weights, weights[1:]):
        if len(earlier) == len(later):
            assert np.max(np.abs(later - earlier)) < 0.1


def test_the_table_reads_saves_and_reads_again(tmp_path):
    path = tmp_path / "weather.toml"
    path.write_text('[cloud_field]\n\n[weather]\npreset = "broken"\nto = "overcast"\nstart_s = 30.0\n')
    scene = load_scene(path)
    assert scene.weather == Weather("broken", "overcast", 30.0, 600.0)
    save_scene(scene, tmp_path / "again.toml")
    assert load_scene(tmp_path / "again.toml").weather == scene.weather
    save_scene(dataclasses.replace(scene, weather=Weather("overcast")), tmp_path / "plain.toml")
    assert load_scene(tmp_path / "plain.toml").weather == Weather("overcast")
    save_scene(Scene(), tmp_path / "none.toml")
    assert "weather" not in (tmp_path / "none.toml").read_text()


@pytest.mark.parametrize(
    "table, field, problem",
    [
        ('preset = "drizzle"', "weather.preset", "'drizzle' is not one of: " + ", ".join(WEATHER_NAMES)),
        ('to = "storm"', "weather.to", "'storm' is not one of: " + ", ".join(WEATHER_NAMES)),
        ("duration_s = 0.5", "weather.duration_s", "must be within [1, 86400], got 0.5"),
        ("start_s = nan", "weather.start_s", "must be finite, got nan"),
        ("preset = 3", "weather.preset", "expected a string, got 3"),
        ("rain = 1", "weather.rain", "unknown key; valid keys: " + ", ".join(TABLE_KEYS["weather"])),
    ],
)
def test_every_key_is_refused_in_one_line_naming_file_and_field(tmp_path, table, field, problem):
    path = tmp_path / "bad.toml"
    path.write_text(f"[cloud_field]\n\n[weather]\n{table}\n")
    assert_file_refused_in_one_line(path, field, problem)


def test_a_weather_without_a_field_is_refused(tmp_path):
    path = tmp_path / "bare.toml"
    path.write_text('[weather]\npreset = "broken"\n')
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert caught.value.field == "weather" and "no [cloud_field]" in caught.value.problem


def test_the_record_refuses_what_the_file_would():
    with pytest.raises(FieldError) as caught:
        Weather("scattered", to="hail")
    assert caught.value.field == "to"
