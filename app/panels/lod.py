"""The LOD panel: the render settings' widgets, made from their `Option`s, and the overlays."""

from __future__ import annotations

import dataclasses
import math

from imgui_bundle import imgui

from app.editor import Editor
from app.viewport import Viewport
from cloudcore.model.settings import AUTO_SCALE, Option, RenderSettings, setting_options


class LodPanel:
    def __init__(self, editor: Editor, viewport: Viewport):
        self.editor, self.viewport = editor, viewport

    def draw(self) -> None:
        """The settings' widgets, in their fields' order, made from their `Option`s (`cloudcore.model.settings`)."""
        editor = self.editor
        settings = editor.settings
        changes = {}
        for name, option in setting_options().items():
            if name in _COMPOUND_WIDGETS:
                changes |= _COMPOUND_WIDGETS[name](settings, option)
            elif option.label is not None:
                changed, value = _setting_widget(option, getattr(settings, name))
                if changed:
                    changes[name] = value
        if changes:
            try:
                editor.settings = dataclasses.replace(settings, **changes)
            except ValueError as error:
                editor.messages.append(str(error))
        imgui.separator_text("Overlays")
        _, self.viewport.show_impostor_outlines = imgui.checkbox(
            "Impostor outlines", self.viewport.show_impostor_outlines
        )
        imgui.same_line()
        _, self.viewport.show_ring_segments = imgui.checkbox("Ring segments", self.viewport.show_ring_segments)


def _tooltip(option: Option) -> None:
    imgui.set_item_tooltip(option.help[:1].upper() + option.help[1:] + ".")


def _setting_widget(option: Option, value):
    """(changed, value) of one setting's combo, checkbox or slider."""
    display = option.zero_display if value == 0 and option.zero_display else option.display
    if option.choices:
        changed, index = imgui.combo(option.label, option.choices.index(value), list(option.choices))
        value = option.choices[index]
    elif isinstance(value, bool):
        changed, value = imgui.checkbox(option.label, value)
    elif isinstance(value, int):
        changed, value = imgui.slider_int(option.label, value, int(option.low), int(option.high), display)
    else:
        changed, value = imgui.slider_float(option.label, value, option.low, option.high, display)
    _tooltip(option)
    return changed, value


def _ring_widgets(settings: RenderSettings, option: Option) -> dict:
    """The ring on or off (an infinite radius) and its radius."""
    ring_on = math.isfinite(settings.ring_radius)
    changed_on, ring_on = imgui.checkbox("Impostor ring", ring_on)
    radius = settings.ring_radius if ring_on else RenderSettings().ring_radius
    changed_radius, radius = imgui.slider_float("Ring radius (m)", radius, 0.0, 20000.0, "%.0f")
    _tooltip(option)
    return {"ring_radius": radius if ring_on else math.inf} if changed_on or changed_radius else {}


def _impostor_size_widgets(settings: RenderSettings, option: Option) -> dict:
    """The smallest and largest impostor texture sides, as powers of two, on one slider."""
    sizes = [int(math.log2(settings.impostor_min_size)), int(math.log2(settings.impostor_max_size))]
    changed, sizes = imgui.slider_int2("Impostor size (log2)", sizes, 3, 12)
    imgui.set_item_tooltip("The smallest and largest impostor texture sides, powers of two.")
    return {"impostor_min_size": 2 ** min(sizes), "impostor_max_size": 2 ** max(sizes)} if changed else {}


def _cloud_scale_widgets(settings: RenderSettings, option: Option) -> dict:
    """The cloud pass's scale chosen per frame by the plan, or set on the slider."""
    chosen = settings.cloud_resolution_scale == AUTO_SCALE
    changed_auto, chosen = imgui.checkbox("Cloud pass scale per frame", chosen)
    imgui.set_item_tooltip("Auto mode chooses the cloud pass's resolution each frame by its predicted cost.")
    held = settings.cloud_resolution_scale if settings.cloud_resolution_scale != AUTO_SCALE else 1.0
    changed_scale, scale = _setting_widget(option, held)
    if chosen and changed_scale:  # the slider moved: a scale set by hand
        chosen = False
    return {"cloud_resolution_scale": AUTO_SCALE if chosen else scale} if changed_auto or changed_scale else {}


#: settings drawn by one widget of their own (the panel leaves their fellows, such as the largest size, out)
_COMPOUND_WIDGETS = {
    "ring_radius": _ring_widgets,
    "impostor_min_size": _impostor_size_widgets,
    "cloud_resolution_scale": _cloud_scale_widgets,
}
