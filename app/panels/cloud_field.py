"""The Cloud field panel: the scene's `[cloud_field]` (Yusov's nested grid to the horizon) and its `[wind]` as
widgets.

Each widget edits the scene through the editor's history, on release (a
slider dragged does not remake the field every frame); the record refuses
what the scene file would (`cloudcore.model.scene.CloudField`), and the refusal
becomes a message.
"""

from __future__ import annotations

import dataclasses

from imgui_bundle import imgui

from app.editor import Editor
from app.panels.widgets import ReleasedSliders
from app.viewport import Viewport
from cloudcore.artist.cloudgen import PRESETS
from cloudcore.field.weather import WEATHER_PRESETS
from cloudcore.model.scene import (
    MAX_LAYERS,
    MAX_RINGS,
    MAX_TURBULENCE_M,
    MAX_WIND_SPEED,
    WEATHER_NAMES,
    CloudField,
    Weather,
    Wind,
)

#: the float sliders: label -> (field, index in a pair or None, low, high, format)
_SLIDERS = {
    "Coverage": ("coverage", None, 0.0, 1.0, "%.2f"),
    "Cell size (m)": ("cell_size", None, 100.0, 5000.0, "%.0f"),
    "Base (m)": ("altitude", 0, 0.0, 10000.0, "%.0f"),
    "Top (m)": ("altitude", 1, 0.0, 12000.0, "%.0f"),
    "Extent x (km)": ("extent", 0, 1.0, 1000.0, "%.0f"),
    "Extent z (km)": ("extent", 1, 1.0, 1000.0, "%.0f"),
    "Centre x (km)": ("centre", 0, -1000.0, 1000.0, "%.1f"),
    "Centre z (km)": ("centre", 1, -1000.0, 1000.0, "%.1f"),
}
#: the sliders in kilometres, the record in metres
_KM = ("Extent x (km)", "Extent z (km)", "Centre x (km)", "Centre z (km)")
_CLOUD_TYPES = tuple(PRESETS)


def _governed_by(weather: Weather) -> set[str]:
    """The field's values the weather sets (either of a change's two weathers): not the panel's to edit."""
    names = [weather.preset] if weather.to is None else [weather.preset, weather.to]
    return {name for preset in names for name in ("coverage", "cloud_type", "altitude", *WEATHER_PRESETS[preset])}


class CloudFieldPanel:
    def __init__(self, editor: Editor, viewport: Viewport, sliders: ReleasedSliders):
        self.editor, self.viewport, self._sliders = editor, viewport, sliders

    def draw(self) -> None:
        self._field()
        self._wind()

    def _wind(self) -> None:
        """`[wind]`: the lowest band's speed and direction (the one band of a wind the panel adds), turbulence and
        gusts; the clouds move as the scene clock runs (the Camera panel's "Scene time")."""
        editor = self.editor
        imgui.separator_text("Wind")
        wind = editor.scene.wind
        if wind is None:
            imgui.text_wrapped("Still air: the clouds stay where they are.")
            if imgui.button("Add wind"):
                editor.edit(dataclasses.replace(editor.scene, wind=Wind()))
            return
        changes: dict = {}
        altitude = wind.bands[0][0]
        if len(wind.bands) > 1:
            imgui.text(f"{len(wind.bands)} bands: the lowest, at {altitude:.0f} m")
        speed = self._sliders.slider("Wind speed", wind.bands[0][1], 0.0, MAX_WIND_SPEED, "%.1f m/s")
        direction = self._sliders.slider("Wind from (deg)", wind.bands[0][2], 0.0, 360.0, "%.0f")
        if speed is not None or direction is not None:
            band = (
                altitude,
                wind.bands[0][1] if speed is None else speed,
                wind.bands[0][2] if direction is None else direction,
            )
            changes["bands"] = (band, *wind.bands[1:])
        for label, name, high in (
            ("Gusts", "gust_amplitude", 1.0),
            ("Turbulence (m)", "turbulence_m", MAX_TURBULENCE_M),
        ):
            value = self._sliders.slider(label, getattr(wind, name), 0.0, high, "%.2f" if high == 1.0 else "%.0f")
            if value is not None:
                changes[name] = value
        if changes:
            scene = editor.scene
            editor.change(lambda: dataclasses.replace(scene, wind=dataclasses.replace(wind, **changes)))
        if imgui.button("Remove wind"):
            editor.edit(dataclasses.replace(editor.scene, wind=None))

    def _weather(self, weather: Weather | None) -> None:
        """`[weather]`: a named weather over the field, and a change to another over the scene clock (the Camera
        panel's "Scene time")."""
        editor = self.editor
        choice = 0 if weather is None else 1 + WEATHER_NAMES.index(weather.preset)
        changed, choice = imgui.combo("Weather", choice, ["the field's own", *WEATHER_NAMES])
        if changed:
            editor.edit(
                dataclasses.replace(editor.scene, weather=None if choice == 0 else Weather(WEATHER_NAMES[choice - 1]))
            )
        if weather is None:
            return
        imgui.text_wrapped("The weather sets the field's coverage, cloud type and altitudes (greyed above).")
        to = 0 if weather.to is None else 1 + WEATHER_NAMES.index(weather.to)
        changed, to = imgui.combo("Changes to", to, ["no change", *WEATHER_NAMES])
        changes: dict = {}
        if changed:
            changes["to"] = None if to == 0 else WEATHER_NAMES[to - 1]
        if weather.to is not None:
            start = self._sliders.slider("Change starts (s)", weather.start_s, 0.0, 3600.0, "%.0f")
            duration = self._sliders.slider("Change lasts (s)", weather.duration_s, 1.0, 3600.0, "%.0f", True)
            if start is not None:
                changes["start_s"] = start
            if duration is not None:
                changes["duration_s"] = duration
        if changes:
            scene = editor.scene
            editor.change(lambda: dataclasses.replace(scene, weather=dataclasses.replace(weather, **changes)))

    def _field(self) -> None:
        editor = self.editor
        field = editor.scene.cloud_field
        if field is None:
            imgui.text_wrapped("No cloud field: clouds generated around the camera to the horizon.")
            if imgui.button("Add cloud field"):
                editor.edit(dataclasses.replace(editor.scene, cloud_field=CloudField()))
            return
        changes: dict = {}
        weather = editor.scene.weather
        # what a named weather sets is shown as it is, not edited (the field's own values come back without it)
        governed = set() if weather is None else _governed_by(weather)
        changed, seed = imgui.input_int("Seed", field.seed)
        if changed:
            changes["seed"] = seed
        for label, (name, index, low, high, fmt) in _SLIDERS.items():
            scale = 1e3 if label in _KM else 1.0
            held = getattr(field, name)
            imgui.begin_disabled(name in governed)
            value = self._sliders.slider(label, (held if index is None else held[index]) / scale, low, high, fmt)
            imgui.end_disabled()
            if value is None:
                continue
            value *= scale
            if index is None:
                changes[name] = value
            else:
                pair = list(changes.get(name, held))
                pair[index] = value
                changes[name] = tuple(pair)
        for label, name, high in (("Rings", "rings", MAX_RINGS), ("Layers", "layers", MAX_LAYERS)):
            imgui.begin_disabled(name in governed)
            value = self._sliders.slider_int(label, getattr(field, name), 1, high)
            imgui.end_disabled()
            if value is not None:
                changes[name] = value
        imgui.begin_disabled("cloud_type" in governed)
        changed, type_index = imgui.combo("Cloud type", _CLOUD_TYPES.index(field.cloud_type), list(_CLOUD_TYPES))
        imgui.end_disabled()
        if changed:
            changes["cloud_type"] = _CLOUD_TYPES[type_index]
        self._weather(weather)
        if changes:
            scene = editor.scene
            editor.change(lambda: dataclasses.replace(scene, cloud_field=dataclasses.replace(field, **changes)))
        if self.viewport.renderer is not None:
            cells = self.viewport.renderer.field_state.cells
            clouds = [cloud for cloud in cells.values() if cloud is not None]
            imgui.text(
                f"{len(cells)} cells made, {len(clouds)} cloudy, {sum(len(c.particles) for c in clouds)} particles"
            )
        if imgui.button("Remove cloud field"):  # its weather with it: a weather without a field is refused
            editor.edit(dataclasses.replace(editor.scene, cloud_field=None, weather=None))
