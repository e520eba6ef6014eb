"""Named weather over a cloud field, and a change of weather over the scene clock (pure).

`[weather]` (`cloudcore.model.scene.Weather`) names one of `WEATHER_PRESETS`, each
a coverage, a cloud type (`cloudcore.artist.cloudgen.PRESETS`) and the band
of altitudes the field's particles lie in; the towering cumulus also the
scale of its clouds (the field's cell size and layers).

A change of weather (`to`) runs over `duration_s` seconds of the scene clock
from `start_s`, s = smoothstep(u) of u the share of it elapsed: the clouds of
the weather before dissipate as those of the weather after form, each field
made once for the whole change (its cells, and their light) and its
particles weighed, so nothing pops.  A field of coverage c forms as Wang's
clouds do (`cloudcore.artist.formation.formed`), in the order its points
turn cloudy as its coverage grows (`cloudcore.field.cells.formation_order`):
its clouds' cores first, their rims and anvils last.  The weather after is
formed to s of its opacity, the weather before to 1 - s, so the cloudy share
of the sky follows c_from + (c_to - c_from) s where their clouds lie apart
(where they overlap, both fields' sites being the same, it shows less), and
the cloud types blend by their shares.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from cloudcore.artist.formation import formed, progress_for_share
from cloudcore.field.cells import formation_order
from cloudcore.field.state import FieldFrame, FieldState, side_by_side, update_field
from cloudcore.maths.ramps import smoothstep
from cloudcore.model.scene import CloudField, Weather
from cloudcore.world.wind import field_drift

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


def change_progress(weather: Weather, time_s: float) -> float:
    """How far the change of weather has run at `time_s`: 0 before it starts (or with none), 1 from its end on."""
    if weather.to is None:
        return 0.0
    return min(max((time_s - weather.start_s) / weather.duration_s, 0.0), 1.0)


def weather_shares(weather: Weather, time_s: float) -> tuple[tuple[str, float], ...]:
    """The named weathers over the field at `time_s` and how far each is formed: one at 1 outside a change, the
    weather before at 1 - s and the one after at s during it."""
    done = float(smoothstep(0.0, 1.0, change_progress(weather, time_s)))
    if weather.to is None or done == 0.0:
        return ((weather.preset, 1.0),)
    if done == 1.0:
        return ((weather.to, 1.0),)
    return ((weather.preset, 1.0 - done), (weather.to, done))


def weather_coverage(weather: Weather, time_s: float) -> float:
    """The sky's cloudy share under the weather at `time_s`: its preset's coverage, blending to that of `to`."""
    return sum(WEATHER_PRESETS[name]["coverage"] * share for name, share in weather_shares(weather, time_s))


def preset_field(field: CloudField, name: str) -> CloudField:
    """`field` with the coverage, cloud type and altitudes (and the scale, where it has one) of the named weather."""
    preset = WEATHER_PRESETS[name]
    scale = {key: preset[key] for key in ("cell_size", "layers") if key in preset}
    return dataclasses.replace(
        field, coverage=preset["coverage"], cloud_type=preset["cloud_type"], altitude=preset["altitude"], **scale
    )


def weather_drift(wind, field: CloudField | None, weather: Weather | None, time_s: float) -> np.ndarray:
    """(3,) metres the field's grid has drifted by `time_s` (`cloudcore.world.wind.field_drift`); during a change of
    weather the two weathers' drifts weighed by their shares, so the clouds never jump as the altitudes change."""
    if field is None or weather is None:
        return field_drift(wind, field, time_s)
    return sum(
        share * field_drift(wind, preset_field(field, name), time_s) for name, share in weather_shares(weather, time_s)
    )


@dataclass(frozen=True)
class WeatherFieldState:
    """The cells made for the last eye of each weather over the field (pure; the renderer holds one between frames):
    one part, or two while the weather changes, each with the particles' formation order and its places in the
    frame; `leading` places of weathers gone come first, so the clouds of the weather that stays keep their indices
    (and their impostors) when the other leaves."""

    names: tuple = (None,)  # per part: its weather's name (None: the field as authored)
    parts: tuple = (FieldState(),)
    places: tuple = (0,)  # per part: the most clouds it has had
    orders: tuple = ((None, None),)  # per part: (the particle places the orders are for, the orders)
    leading: int = 0

    @property
    def in_force(self) -> FieldState:
        """The part of the weather that is, or is coming: the cells the editor and the tests look at."""
        return self.parts[-1]


def update_weather_field(
    field: CloudField, weather: Weather | None, time_s: float, eye, state: WeatherFieldState = WeatherFieldState()
) -> tuple[FieldFrame, WeatherFieldState]:
    """The field's clouds for `eye` under the weather at `time_s` (`cloudcore.field.state.update_field` for each
    weather over it) and the state to carry on."""
    shares = ((None, 1.0),) if weather is None else weather_shares(weather, time_s)
    names = tuple(name for name, _ in shares)
    kept = [state.names.index(name) if name in state.names else None for name in names]
    if kept[0] is None:  # a weather not seen before comes first: the frame's places start anew
        leading = 0
    else:  # the places of the weathers before the first one kept become holes
        leading = state.leading + sum(state.places[: kept[0]])
    frames, weights, parts, places, orders = [], [], [], [], []
    for (name, share), index in zip(shares, kept):
        part_field = field if name is None else preset_field(field, name)
        held = (
            (FieldState(), 0, (None, None))
            if index is None
            else (state.parts[index], state.places[index], state.orders[index])
        )
        frame, part = update_field(part_field, eye, held[0])
        order, weighed = held[2], frame.weights
        if share < 1.0:
            if order[0] is not part.particle_xz:  # the cells changed: their particles' order, once
                order = (part.particle_xz, formation_order(part_field, part.particle_xz[:, 0], part.particle_xz[:, 1]))
            weighed = weighed * formed(progress_for_share(share), order[1])
        frames.append(frame)
        weights.append(weighed)
        parts.append(part)
        places.append(max(held[1], len(frame.clouds)))
        orders.append(order)
    state = WeatherFieldState(names, tuple(parts), tuple(places), tuple(orders), leading)
    return side_by_side(frames, weights, places, leading), state
