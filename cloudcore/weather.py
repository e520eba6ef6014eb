"""Named weather over a cloud field, and a change of weather over the scene clock (pure).

`[weather]` (`cloudcore.scene.Weather`) names one of `WEATHER_PRESETS`, each
a coverage, a cloud type (`cloudcore.artist.cloudgen.PRESETS`) and the band
of altitudes the field's particles lie in; the towering cumulus also the
scale of its clouds (the field's cell size and layers).  A change of weather (`to`) runs
over `duration_s` seconds of the scene clock from `start_s`: the coverage
follows c(t) = c_from + (c_to - c_from) smoothstep(u), u the share of the
change elapsed, and the cloud type and altitudes switch halfway.

The field is made again whenever its parameters change (every cell, and its
light), so the coverage is handed to it in steps of `COVERAGE_STEP`: a
change from scattered to overcast remakes the field 11 times, not each
frame; a cell's cloud appears or goes at the step its density crosses the
coverage's threshold (`cloudcore.field.cells`).
"""

from __future__ import annotations

import dataclasses

from cloudcore.ramps import smoothstep
from cloudcore.scene import CloudField, Weather

#: name -> what it sets of the field: coverage, cloud type, altitude (bottom, top) in metres, and where the weather's
#: clouds are of another scale than the field's own, its cell size (a cloud is about three cells across) and layers
WEATHER_PRESETS = {
    "fair_weather_cumulus": {"coverage": 0.25, "cloud_type": "cumulus_humilis", "altitude": (1200.0, 2000.0)},
    "scattered": {"coverage": 0.4, "cloud_type": "cumulus_humilis", "altitude": (1200.0, 2600.0)},
    "broken": {"coverage": 0.7, "cloud_type": "cumulus_congestus", "altitude": (1000.0, 3200.0)},
    "overcast": {"coverage": 0.95, "cloud_type": "stratocumulus", "altitude": (800.0, 1600.0)},
    # thunderstorms: towers ten kilometres wide up to the tropopause under their anvils, far apart
    "towering_cumulus": {
        "coverage": 0.15,
        "cloud_type": "cumulonimbus",
        "altitude": (1000.0, 10000.0),
        "cell_size": 2000.0,
        "layers": 8,
    },
}
#: the coverage reaches the field in steps of this: each step remakes the field
COVERAGE_STEP = 0.05


def change_progress(weather: Weather, time_s: float) -> float:
    """How far the change of weather has run at `time_s`: 0 before it starts (or with none), 1 from its end on."""
    if weather.to is None:
        return 0.0
    return min(max((time_s - weather.start_s) / weather.duration_s, 0.0), 1.0)


def weather_coverage(weather: Weather, time_s: float) -> float:
    """The coverage of the weather at `time_s`: its preset's, blending to that of `to` by a smoothstep in time."""
    start = WEATHER_PRESETS[weather.preset]["coverage"]
    if weather.to is None:
        return start
    end = WEATHER_PRESETS[weather.to]["coverage"]
    return start + (end - start) * float(smoothstep(0.0, 1.0, change_progress(weather, time_s)))


def field_under_weather(field: CloudField, weather: Weather | None, time_s: float) -> CloudField:
    """`field` with the coverage, cloud type and altitudes the weather gives at `time_s` (its coverage in steps of
    `COVERAGE_STEP`); `field` itself without weather."""
    if weather is None:
        return field
    in_force = weather.to if weather.to is not None and change_progress(weather, time_s) >= 0.5 else weather.preset
    preset = WEATHER_PRESETS[in_force]
    coverage = min(max(round(weather_coverage(weather, time_s) / COVERAGE_STEP) * COVERAGE_STEP, 0.0), 1.0)
    scale = {name: preset[name] for name in ("cell_size", "layers") if name in preset}
    return dataclasses.replace(
        field, coverage=coverage, cloud_type=preset["cloud_type"], altitude=preset["altitude"], **scale
    )
