"""Named weather over a cloud field (`cloudcore.weather`, `[weather]`): the presets, a change of weather whose
coverage follows its curve, and the keys refused in one line."""

import dataclasses

import numpy as np
import pytest

from cloudcore.errors import FieldError, SceneError
from cloudcore.ramps import smoothstep
from cloudcore.scene import WEATHER_NAMES, CloudField, Scene, Weather
from cloudcore.scenefile import TABLE_KEYS, load_scene, save_scene
from cloudcore.weather import COVERAGE_STEP, WEATHER_PRESETS, field_under_weather, weather_coverage
from tests.conftest import assert_file_refused_in_one_line

FIELD = CloudField(seed=4, coverage=0.1, rings=2, cloud_type="cirrus", altitude=(5000.0, 6000.0))


def test_every_named_weather_sets_the_field_s_coverage_type_and_altitudes():
    assert tuple(WEATHER_PRESETS) == WEATHER_NAMES
    cumulus_to_overcast = [WEATHER_PRESETS[name]["coverage"] for name in WEATHER_NAMES[:4]]
    assert cumulus_to_overcast == sorted(cumulus_to_overcast)
    for name in WEATHER_NAMES:
        field = field_under_weather(FIELD, Weather(name), 123.0)
        preset = WEATHER_PRESETS[name]
        assert field.coverage == pytest.approx(preset["coverage"], abs=1e-12)
        assert (field.cloud_type, field.altitude) == (preset["cloud_type"], preset["altitude"])
        scale = (preset.get("cell_size", FIELD.cell_size), preset.get("layers", FIELD.layers))
        assert (field.seed, field.rings, field.cell_size, field.layers) == (FIELD.seed, FIELD.rings, *scale)
    # thunderstorms' clouds are of another scale than the field's cumulus: larger cells, every layer
    towering = field_under_weather(FIELD, Weather("towering_cumulus"), 0.0)
    assert towering.cell_size > FIELD.cell_size and towering.layers == 8
    assert field_under_weather(FIELD, None, 50.0) is FIELD


def test_a_change_of_weather_s_coverage_follows_its_curve():
    change = Weather("scattered", to="overcast", start_s=60.0, duration_s=600.0)
    times = np.linspace(0.0, 800.0, 801)
    curve = 0.4 + (0.95 - 0.4) * smoothstep(0.0, 1.0, (times - 60.0) / 600.0)
    coverage = np.array([weather_coverage(change, t) for t in times])
    np.testing.assert_allclose(coverage, curve, atol=1e-12)
    assert coverage[0] == 0.4 and coverage[-1] == 0.95 and np.all(np.diff(coverage) >= 0.0)
    # the field gets it in steps, each within half a step of the curve: a few remakes, not one a frame
    handed = np.array([field_under_weather(FIELD, change, t).coverage for t in times])
    assert np.max(np.abs(handed - curve)) <= COVERAGE_STEP / 2 + 1e-12
    assert len(np.unique(np.round(handed, 9))) == 12  # 0.40, 0.45, ... 0.95
    # the type and altitudes switch halfway
    assert field_under_weather(FIELD, change, 359.0).cloud_type == "cumulus_humilis"
    assert field_under_weather(FIELD, change, 360.0).cloud_type == "stratocumulus"


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
