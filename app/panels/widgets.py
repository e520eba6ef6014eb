"""Widgets the panels share."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from imgui_bundle import imgui

#: room at a widget's right for its label, in ems: ImGui's default gives a widget two thirds of the panel, which at
#: the editor's default size (panels 367 pixels wide) cut the LOD panel's longer labels in the middle; the longest
#: labels ("Screen impostor scale", "Regeneration budget") take 8.6 and 8.3 ems
LABEL_EMS = 10.5
#: the narrowest a widget is made to leave its label room: a narrower panel cuts the labels instead
_FEWEST_EMS = 6.0


@contextmanager
def labels_in_full() -> Iterator[None]:
    """Within the body, widgets leave `LABEL_EMS` at their right for their labels."""
    em = imgui.get_font_size()
    imgui.push_item_width(max(imgui.get_content_region_avail().x - LABEL_EMS * em, _FEWEST_EMS * em))
    try:
        yield
    finally:
        imgui.pop_item_width()


def bounded_slider(
    label: str, value: float, low: float, high: float, fmt: str = "%.3f", logarithmic: bool = False
) -> tuple[bool, float]:
    """imgui.slider_float whose value stays within [low, high] when a number is typed (ctrl+click): ImGui takes
    any by default, and a typed brush rate of 0, a fly speed of 1e38 or an orbit step of 1e39 raised every frame
    or flung the camera out of the world.  A number the clamp cannot place (NaN) leaves the value as it was.
    `logarithmic` spreads a range of several decades along the slider."""
    flags = imgui.SliderFlags_.always_clamp | (imgui.SliderFlags_.logarithmic if logarithmic else 0)
    changed, typed = imgui.slider_float(label, value, low, high, fmt, flags)
    if not low <= typed <= high:
        return False, value
    return changed, typed


class ReleasedSliders:
    """Sliders whose new value counts once, on release: dragging does not re-shade every frame or fill the
    undo history.  While one is dragged, `dragged` gives the value shown (the viewport can follow it)."""

    def __init__(self):
        self._dragging: dict[str, float] = {}

    def slider(
        self, label: str, value: float, low: float, high: float, fmt: str = "%.3f", logarithmic: bool = False
    ) -> float | None:
        """The slider `label` (`bounded_slider`'s); returns the released value, or None."""
        changed, shown = bounded_slider(label, self._dragging.get(label, value), low, high, fmt, logarithmic)
        return self._released(label, changed, shown)

    def slider_int(self, label: str, value: int, low: int, high: int) -> int | None:
        """The integer slider `label`; returns the released value, or None."""
        shown = int(self._dragging.get(label, value))
        changed, shown = imgui.slider_int(label, shown, low, high, flags=imgui.SliderFlags_.always_clamp)
        released = self._released(label, changed, shown)
        return None if released is None else int(released)

    def _released(self, label: str, changed: bool, shown):
        """The value of the slider just drawn once it is let go after an edit, else None."""
        if changed:
            self._dragging[label] = shown
        if imgui.is_item_deactivated_after_edit():
            return self._dragging.pop(label, shown)
        if not imgui.is_item_active():
            self._dragging.pop(label, None)
        return None

    def dragged(self, label: str) -> float | None:
        """The value the slider `label` shows while it is being dragged, else None."""
        return self._dragging.get(label)
