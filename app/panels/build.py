"""The Build panel: Wang's box fill and the cloud presets."""

from __future__ import annotations

from imgui_bundle import imgui

from app.editor import Editor
from app.panels.widgets import bounded_slider
from cloudcore.artist.cloudgen import PRESETS, TYPICAL_CULL_FRACTION
from cloudcore.scenes.editing import add_preset_cloud, fill_box, pick_ray, point_at_altitude


class BuildPanel:
    def __init__(self, editor: Editor):
        self.editor = editor
        # the artist's box, its sprites, and the preset a new cloud is made from
        self.box_centre = [float(v) for v in editor.camera.look_at]
        self.box_size = [800.0, 400.0, 800.0]
        self.box_particle_radius = 60.0
        self.box_count = 300
        self.box_default_cull = True  # Wang's third of the sprite size
        self.box_cull_distance = TYPICAL_CULL_FRACTION * 2.0 * self.box_particle_radius
        self.box_seed = 0
        self.preset = 0
        self.preset_scale = 1.0

    def draw(self) -> None:
        editor = self.editor
        _, self.box_centre = imgui.input_float3("Box centre (m)", self.box_centre, "%.0f")
        if imgui.button("Centre on the view"):
            self._centre_box_on_view()
        _, self.box_size = imgui.input_float3("Box size (m)", self.box_size, "%.0f")
        _, self.box_particle_radius = imgui.input_float("Sprite radius (m)", self.box_particle_radius)
        _, self.box_count = imgui.input_int("Sprites", self.box_count, 10, 100)
        _, self.box_default_cull = imgui.checkbox("Cull at a third of the sprite size", self.box_default_cull)
        if self.box_default_cull:
            self.box_cull_distance = TYPICAL_CULL_FRACTION * 2.0 * self.box_particle_radius
        imgui.begin_disabled(self.box_default_cull)
        _, self.box_cull_distance = imgui.input_float("Cull distance (m)", self.box_cull_distance)
        imgui.end_disabled()
        _, self.box_seed = imgui.input_int("Seed", self.box_seed)
        if editor.selected_cloud is not None:
            if imgui.button("Fill the selected cloud"):
                self._fill(editor.selected_cloud)
            imgui.same_line()
        if imgui.button("Fill a new cloud"):
            self._fill(None)
        imgui.separator_text("Cloud presets")
        names = list(PRESETS)
        _, self.preset = imgui.combo("Preset", self.preset, names)
        _, self.preset_scale = bounded_slider("Scale", self.preset_scale, 0.1, 3.0)
        if imgui.button("New cloud from preset"):
            try:
                scene = add_preset_cloud(
                    editor.scene, names[self.preset], self.box_centre, self.preset_scale, self.box_seed
                )
            except ValueError as error:
                editor.messages.append(f"could not make a {names[self.preset]}: {error}")
                return
            if not editor.edit(scene):
                return
            editor.selected_cloud = len(editor.scene.clouds) - 1
            editor.messages.append(f"added {editor.scene.clouds[-1].name}, base at the box centre")
            self.box_seed += 1

    def _fill(self, cloud_index: int | None) -> None:
        editor = self.editor
        try:
            scene, filled = fill_box(
                editor.scene,
                cloud_index,
                self.box_centre,
                self.box_size,
                self.box_particle_radius,
                self.box_count,
                self.box_cull_distance,
                self.box_seed,
            )
        except ValueError as error:
            editor.messages.append(f"could not fill the box: {error}")
            return
        had = len(editor.scene.clouds[cloud_index].particles) if cloud_index is not None else 0
        added = len(scene.clouds[filled].particles) - had
        if not editor.edit(scene):
            return
        editor.selected_cloud = filled
        editor.messages.append(f"box fill: {added} of {self.box_count} sprites kept in {scene.clouds[filled].name}")
        self.box_seed += 1  # the next fill scatters differently

    def _centre_box_on_view(self) -> None:
        """The box centre where the middle of the view meets the placement altitude."""
        editor = self.editor
        # the ray through the middle of the view is the same at any aspect ratio
        point = point_at_altitude(*pick_ray(editor.camera, 1.0, 0.5, 0.5), editor.placement_altitude)
        if point is None:
            editor.messages.append("the middle of the view never reaches the placement altitude")
            return
        self.box_centre = [float(v) for v in point]
