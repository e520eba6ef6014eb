"""The Lighting panel: the time of day and the shading, the viewport following a slider as it is dragged."""

from __future__ import annotations

import dataclasses

from imgui_bundle import imgui

from app.editor import Editor
from app.panels.widgets import ReleasedSliders
from cloudcore.light.phase import PHASE_NAMES
from cloudcore.light.shading import EYE_PASSES, LIGHT_PASSES

#: the shading sliders: label -> (`Shading` field, low, high)
_SHADING_SLIDERS = {
    "Albedo": ("albedo", 0.0, 1.0),
    "Optical depth": ("optical_depth", 0.0, 50.0),
    "g": ("g", -0.99, 0.99),
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
        changes = {key: value for key, value in changes.items() if value is not None}
        if changed_light_pass:
            changes["light_pass"] = LIGHT_PASSES[light_pass_index]
        if changed_phase:
            changes["phase"] = PHASE_NAMES[phase_index]
        if changed_eye_pass:
            changes["eye_pass"] = EYE_PASSES[eye_pass_index]
        if changes:
            editor.edit(dataclasses.replace(scene, shading=dataclasses.replace(shading, **changes)))
