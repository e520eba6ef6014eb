"""The Clouds panel: the clouds, the selected one's optical depth and particle size, the viewport's tools."""

from __future__ import annotations

import dataclasses

from imgui_bundle import imgui

from app.editor import TOOLS, Editor
from app.panels.widgets import ReleasedSliders, bounded_slider
from cloudcore.scenes.editing import add_cloud, delete_cloud, replace_cloud, with_mean_radius


class CloudsPanel:
    def __init__(self, editor: Editor, sliders: ReleasedSliders):
        self.editor, self._sliders = editor, sliders

    def draw(self) -> None:
        editor = self.editor
        scene = editor.scene
        imgui.text(f"{len(scene.clouds)} clouds, {scene.particle_count} particles")
        names = [f"{c.name} ({len(c.particles)})" for c in scene.clouds]
        if names:
            _, editor.selected_cloud = imgui.combo("Cloud", editor.selected_cloud or 0, names)
        if imgui.button("Add cloud") and editor.edit(add_cloud(scene)):
            editor.selected_cloud = len(editor.scene.clouds) - 1
        if editor.selected_cloud is not None:
            imgui.same_line()
            if imgui.button("Delete cloud"):
                editor.edit(delete_cloud(scene, editor.selected_cloud))
        if editor.selected_cloud is not None:
            cloud = editor.scene.clouds[editor.selected_cloud]
            tau = scene.shading.optical_depth if cloud.optical_depth is None else cloud.optical_depth
            tau = self._sliders.slider("Cloud optical depth", tau, 0.0, 50.0)
            if tau is not None:
                editor.edit(
                    replace_cloud(scene, editor.selected_cloud, dataclasses.replace(cloud, optical_depth=float(tau)))
                )
            if len(cloud.particles):
                radius = self._sliders.slider("Mean particle radius", float(cloud.radii.mean()), 1.0, 1000.0, "%.1f m")
                if radius is not None:
                    editor.edit(with_mean_radius(scene, editor.selected_cloud, radius))
        imgui.separator_text("Viewport tool (left mouse)")
        for number, (key, label) in enumerate(TOOLS):
            if number % 2:
                imgui.same_line()
            if imgui.radio_button(label, editor.tool == key):
                editor.tool = key
        if imgui.radio_button("On the altitude plane", not editor.on_cloud_surface):
            editor.on_cloud_surface = False
        imgui.same_line()
        if imgui.radio_button("On the cloud's surface", editor.on_cloud_surface):
            editor.on_cloud_surface = True
        _, editor.placement_altitude = bounded_slider("Altitude (m)", editor.placement_altitude, 0.0, 5000.0)
        _, editor.particle_radius = bounded_slider("Particle radius (m)", editor.particle_radius, 1.0, 500.0)
        if imgui.radio_button("Brush adds", not editor.brush_erases):
            editor.brush_erases = False
        imgui.same_line()
        if imgui.radio_button("Brush erases", editor.brush_erases):
            editor.brush_erases = True
        _, editor.brush_radius = bounded_slider("Brush radius (m)", editor.brush_radius, 10.0, 3000.0, "%.0f")
        _, editor.brush_rate = bounded_slider("Brush rate (per s)", editor.brush_rate, 1.0, 500.0, "%.0f")
        imgui.text_wrapped(
            "Move: drag in the viewport (Shift: in the screen's plane). Delete removes the picked "
            "particle, or else the selected cloud."
        )
