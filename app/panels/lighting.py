"""The Lighting panel: the time of day and the shading, the viewport following a slider as it is dragged."""

from __future__ import annotations

import dataclasses

from imgui_bundle import imgui

from app.editor import Editor
from app.panels.widgets import ReleasedSliders
from cloudcore.light.lighting import SKIES
from cloudcore.light.phase import PHASE_NAMES
from cloudcore.light.shading import EYE_PASSES, LIGHT_PASSES
from cloudcore.model.scene import Air
from cloudcore.scenes.limits import FIELD_RANGES

#: the shading sliders: label -> (`Shading` field, low, high)
_SHADING_SLIDERS = {
    "Albedo": ("albedo", 0.0, 1.0),
    "Optical depth": ("optical_depth", 0.0, 50.0),
    "g": ("g", -0.99, 0.99),
}

#: the air's sliders: label -> (`Air` field, format, logarithmic); their ranges are the scene file's
#: (`cloudcore.scenes.limits.FIELD_RANGES`).  The haze spans clear air to a hundred times its aerosols, and the altitude
#: sea level to 50 km: decades a linear slider would crowd into its first pixels
_AIR_SLIDERS = {
    "Haze (x Earth's aerosols)": ("mie_density_scale", "%.2f", True),
    "Ground albedo": ("ground_albedo", "%.2f", False),
    "Origin altitude (m)": ("origin_altitude_m", "%.0f", True),
}


class LightingPanel:
    def __init__(self, editor: Editor, sliders: ReleasedSliders):
        self.editor, self._sliders = editor, sliders

    def draw(self) -> None:
        editor = self.editor
        scene = editor.scene
        hours = editor.time_of_day if editor.time_of_day is not None else 12.0
        hours = self._sliders.slider("Time of day", hours, 0.0, 24.0, "%.2f h")
        if hours is not None:
            editor.set_time_of_day(hours)
        shading = scene.shading
        changes = {
            field: self._sliders.slider(label, getattr(shading, field), low, high)
            for label, (field, low, high) in _SHADING_SLIDERS.items()
        }
        # the viewport follows a slider being dragged (`cloudcore.light.relighting`); the edit is made on release
        dragged = {
            field: self._sliders.dragged(label)
            for label, (field, _, _) in _SHADING_SLIDERS.items()
            if self._sliders.dragged(label) is not None
        }
        dragged_hours = self._sliders.dragged("Time of day")
        editor.dragged_look = (
            None
            if not dragged and dragged_hours is None
            else (
                dataclasses.replace(shading, **dragged),
                scene.lighting
                if dragged_hours is None
                else dataclasses.replace(scene.lighting, time_of_day=float(dragged_hours)),
            )
        )
        changed_phase, phase_index = imgui.combo("Phase function", PHASE_NAMES.index(shading.phase), list(PHASE_NAMES))
        changed_eye_pass, eye_pass_index = imgui.combo("Eye pass", EYE_PASSES.index(shading.eye_pass), list(EYE_PASSES))
        imgui.set_item_tooltip(
            "harris: Harris's eye scattering; saturated: its scattering saturated for opaque particles and the "
            "ambient light a thick medium's (closer to the path-traced truth: docs/shading.md); yusov: the light "
            "leaving Yusov's precomputed reference particle (its tables ship for Rayleigh; another phase "
            "function or g takes about a minute to build once, then comes from the cache)."
        )
        changed_light_pass, light_pass_index = imgui.combo(
            "Light pass", LIGHT_PASSES.index(shading.light_pass), list(LIGHT_PASSES)
        )
        imgui.set_item_tooltip(
            "harris: the light reaching each particle by Harris's multiple forward scattering; occlusion: by "
            "Yusov's light-space occlusion estimate (with the yusov eye pass, Yusov's model)."
        )
        changed_bounce, ground_bounce = imgui.checkbox("Ground bounce", shading.ground_bounce)
        imgui.set_item_tooltip(
            "The clouds lit from below by the sunlit ground, under their own shadows, in place of the ambient's lower "
            "half (closer to the path-traced truth under a thick cloud: docs/shading.md#the-grounds-bounce)."
        )
        changes = {key: value for key, value in changes.items() if value is not None}
        if changed_bounce:
            changes["ground_bounce"] = ground_bounce
        if changed_light_pass:
            changes["light_pass"] = LIGHT_PASSES[light_pass_index]
        if changed_phase:
            changes["phase"] = PHASE_NAMES[phase_index]
        if changed_eye_pass:
            changes["eye_pass"] = EYE_PASSES[eye_pass_index]
        if changes:
            editor.edit(dataclasses.replace(scene, shading=dataclasses.replace(shading, **changes)))
        self._draw_air()

    def _draw_air(self) -> None:
        """The air the sky and the sun's light come through (docs/atmosphere.md): each change one edit, made on
        release (a new air builds its tables: a fraction of a second, once per air)."""
        imgui.separator_text("Air")
        scene = self.editor.scene
        air = scene.lighting.air
        changed_sky, sky_index = imgui.combo("Sky", SKIES.index(air.sky), list(SKIES))
        imgui.set_item_tooltip(
            "physical: Hillaire's atmosphere gives the sky, the sun's and the sky's light and the air between the "
            "eye and what it sees; gradient: the two-colour sky and heuristic light of before (older pictures)."
        )
        changes = {"sky": SKIES[sky_index]} if changed_sky else {}
        for label, (field, fmt, logarithmic) in _AIR_SLIDERS.items():
            low, high = FIELD_RANGES[Air, field]
            released = self._sliders.slider(label, getattr(air, field), low, high, fmt, logarithmic)
            if released is not None:
                changes[field] = float(released)
        if changes:
            lighting = dataclasses.replace(scene.lighting, air=dataclasses.replace(air, **changes))
            self.editor.edit(dataclasses.replace(scene, lighting=lighting))
