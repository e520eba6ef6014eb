"""The editor's panels: each reads and edits the `Editor` and calls the engine; no rendering maths here."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
from imgui_bundle import imgui, implot

from app.editor import TOOLS, Editor, recovery_path
from app.record_job import RecordJob
from app.viewport import Viewport
from cloudcore.cloudgen import PRESETS, TYPICAL_CULL_FRACTION
from cloudcore.editing import (
    add_cloud,
    add_preset_cloud,
    delete_cloud,
    fill_box,
    pick_ray,
    point_at_altitude,
    replace_cloud,
    with_mean_radius,
)
from cloudcore.errors import SceneError
from cloudcore.navigation import orbited
from cloudcore.phase import PHASE_NAMES
from cloudcore.settings import Option, RenderSettings, setting_options

#: the Lighting panel's shading sliders: label -> (`Shading` field, low, high)
_SHADING_SLIDERS = {
    "Albedo": ("albedo", 0.0, 1.0),
    "Optical depth": ("optical_depth", 0.0, 50.0),
    "g": ("g", -0.99, 0.99),
}


class Panels:
    def __init__(self, editor: Editor, viewport: Viewport):
        self.editor, self.viewport = editor, viewport
        self.file_field = str(editor.path or "")
        self.orbit_step_deg = 1.0
        self._dragging: dict[str, float] = {}
        # box fill (Wang): the artist's box, its sprites, and the preset a new cloud is made from
        self.box_centre = [float(v) for v in editor.camera.look_at]
        self.box_size = [800.0, 400.0, 800.0]
        self.box_particle_radius = 60.0
        self.box_count = 300
        self.box_default_cull = True  # Wang's third of the sprite size
        self.box_cull_distance = TYPICAL_CULL_FRACTION * 2.0 * self.box_particle_radius
        self.box_seed = 0
        self.preset = 0
        self.preset_scale = 1.0
        # recording the chosen camera path
        self.record_out = ""
        self.record_size = [640, 480]
        self.record_fps = 30.0
        self.record_job: RecordJob | None = None

    def _slider_on_release(self, label: str, value: float, low: float, high: float, fmt: str = "%.3f"):
        """A slider whose new value counts once, on release: dragging does not re-shade every frame
        or fill the undo history.  Returns the released value, or None."""
        shown = self._dragging.get(label, value)
        changed, shown = imgui.slider_float(label, shown, low, high, fmt)
        if changed:
            self._dragging[label] = shown
        if imgui.is_item_deactivated_after_edit():
            return self._dragging.pop(label, shown)
        if not imgui.is_item_active():
            self._dragging.pop(label, None)
        return None

    # --- Scene ----------------------------------------------------------------------------------------
    def scene(self) -> None:
        editor = self.editor
        imgui.text(f"{editor.path or '(unsaved scene)'}{' *' if editor.dirty else ''}")
        _, self.file_field = imgui.input_text("File", self.file_field)
        if imgui.button("Open"):
            editor.open_file(Path(self.file_field))
        imgui.same_line()
        if imgui.button("Save"):
            editor.save()
        imgui.same_line()
        if imgui.button("Save as"):
            editor.save(Path(self.file_field))
        imgui.same_line()
        if imgui.button("Undo"):
            editor.undo()
        imgui.same_line()
        if imgui.button("Redo"):
            editor.redo()
        if editor.path is not None and recovery_path(editor.path).exists():
            if imgui.button("Recover unsaved edits"):
                editor.recover()
            imgui.set_item_tooltip(f"load {recovery_path(editor.path)}, written before the last session ended")
        for path in editor.recent[1:]:
            if imgui.small_button(f"recent: {path}"):
                self.file_field = str(path)
                editor.open_file(path)
        imgui.separator()
        for message in reversed(editor.messages):
            imgui.text_wrapped(message)

    # --- Clouds, the viewport's tools, particle placement ---------------------------------------------------
    def clouds(self) -> None:
        editor = self.editor
        scene = editor.scene
        imgui.text(f"{len(scene.clouds)} clouds, {scene.particle_count} particles")
        names = [f"{c.name} ({len(c.particles)})" for c in scene.clouds]
        if names:
            _, editor.selected_cloud = imgui.combo("Cloud", editor.selected_cloud or 0, names)
        if imgui.button("Add cloud"):
            editor.edit(add_cloud(scene))
            editor.selected_cloud = len(editor.scene.clouds) - 1
        if editor.selected_cloud is not None:
            imgui.same_line()
            if imgui.button("Delete cloud"):
                editor.edit(delete_cloud(scene, editor.selected_cloud))
        if editor.selected_cloud is not None:
            cloud = editor.scene.clouds[editor.selected_cloud]
            tau = scene.shading.optical_depth if cloud.optical_depth is None else cloud.optical_depth
            tau = self._slider_on_release("Cloud optical depth", tau, 0.0, 50.0)
            if tau is not None:
                editor.edit(
                    replace_cloud(scene, editor.selected_cloud, dataclasses.replace(cloud, optical_depth=float(tau)))
                )
            if len(cloud.particles):
                radius = self._slider_on_release(
                    "Mean particle radius", float(cloud.radii.mean()), 1.0, 1000.0, "%.1f m"
                )
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
        _, editor.placement_altitude = imgui.slider_float("Altitude (m)", editor.placement_altitude, 0.0, 5000.0)
        _, editor.particle_radius = imgui.slider_float("Particle radius (m)", editor.particle_radius, 1.0, 500.0)
        if imgui.radio_button("Brush adds", not editor.brush_erases):
            editor.brush_erases = False
        imgui.same_line()
        if imgui.radio_button("Brush erases", editor.brush_erases):
            editor.brush_erases = True
        _, editor.brush_radius = imgui.slider_float("Brush radius (m)", editor.brush_radius, 10.0, 3000.0, "%.0f")
        _, editor.brush_rate = imgui.slider_float("Brush rate (per s)", editor.brush_rate, 1.0, 500.0, "%.0f")
        imgui.text_wrapped(
            "Move: drag in the viewport (Shift: in the screen's plane). Delete removes the picked "
            "particle, or else the selected cloud."
        )

    # --- Build: Wang's box fill and cloud presets ---------------------------------------------------------
    def build(self) -> None:
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
        _, self.preset_scale = imgui.slider_float("Scale", self.preset_scale, 0.1, 3.0)
        if imgui.button("New cloud from preset"):
            try:
                editor.edit(
                    add_preset_cloud(
                        editor.scene, names[self.preset], self.box_centre, self.preset_scale, self.box_seed
                    )
                )
            except ValueError as error:
                editor.messages.append(f"could not make a {names[self.preset]}: {error}")
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
        editor.edit(scene)
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

    # --- Lighting -------------------------------------------------------------------------------------------
    def lighting(self) -> None:
        editor = self.editor
        scene = editor.scene
        hours = editor.time_of_day if editor.time_of_day is not None else 12.0
        hours = self._slider_on_release("Time of day", hours, 0.0, 24.0, "%.2f h")
        if hours is not None:
            editor.set_time_of_day(hours)
        shading = scene.shading
        changes = {
            field: self._slider_on_release(label, getattr(shading, field), low, high)
            for label, (field, low, high) in _SHADING_SLIDERS.items()
        }
        # the viewport follows a slider being dragged (`cloudcore.relighting`); the edit is made on release
        dragged = {
            field: self._dragging[label] for label, (field, _, _) in _SHADING_SLIDERS.items() if label in self._dragging
        }
        dragged_hours = self._dragging.get("Time of day")
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
        changes = {key: value for key, value in changes.items() if value is not None}
        if changed_phase:
            changes["phase"] = PHASE_NAMES[phase_index]
        if changes:
            editor.edit(dataclasses.replace(scene, shading=dataclasses.replace(shading, **changes)))

    # --- LOD ------------------------------------------------------------------------------------------------
    def lod(self) -> None:
        """The settings' widgets, in their fields' order, made from their `Option`s (`cloudcore.settings`)."""
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

    # --- Camera ---------------------------------------------------------------------------------------------
    def camera(self) -> None:
        editor = self.editor
        camera = editor.camera
        imgui.text("eye " + ", ".join(f"{v:.0f}" for v in camera.position))
        changed, fov = imgui.slider_float("Field of view", camera.fov_y_deg, 5.0, 120.0)
        if changed:
            editor.camera = dataclasses.replace(camera, fov_y_deg=fov)
        _, self.viewport.fly_speed = imgui.slider_float("Fly speed (m/s)", self.viewport.fly_speed, 10.0, 3000.0)
        _, self.orbit_step_deg = imgui.slider_float("Orbit step (deg)", self.orbit_step_deg, 0.01, 10.0)
        if imgui.button("Orbit left"):
            editor.camera = orbited(editor.camera, -self.orbit_step_deg)
        imgui.same_line()
        if imgui.button("Orbit right"):
            editor.camera = orbited(editor.camera, self.orbit_step_deg)
        if imgui.button("Reset to the scene's camera"):
            editor.camera = editor.scene.camera
        if editor.scene_duration_s > 0.0:
            _, editor.scene_time_s = imgui.slider_float(
                "Scene time (s)", editor.scene_time_s, 0.0, editor.scene_duration_s
            )
        self._camera_paths()

    def _camera_paths(self) -> None:
        editor = self.editor
        imgui.separator_text("Camera path")
        names = [p.name for p in editor.scene.camera_paths]
        if not names:
            imgui.text("the scene has no camera paths")
            return
        current = names.index(editor.camera_path_name) if editor.camera_path_name in names else 0
        changed, current = imgui.combo("Path", current, names)
        if changed or editor.camera_path_name not in names:
            editor.camera_path_name, editor.path_time_s, editor.playing = names[current], 0.0, False
        if imgui.button("Play"):
            editor.play()
        imgui.same_line()
        if imgui.button("Pause"):
            editor.playing = False
        duration = editor.scene.camera_path(editor.camera_path_name).duration
        changed, seconds = imgui.slider_float("Path time (s)", editor.path_time_s, 0.0, duration, "%.2f")
        if changed:
            editor.playing = False
            editor.show_path_time(seconds)
        self._recording(editor.camera_path_name)

    def _recording(self, path_name: str) -> None:
        editor = self.editor
        if not self.record_out:
            stem = editor.path.stem if editor.path else "scene"
            self.record_out = f"{stem}-{path_name}.mp4"
        _, self.record_out = imgui.input_text("Video", self.record_out)
        _, self.record_size = imgui.input_int2("Size (px)", self.record_size)
        _, self.record_fps = imgui.input_float("Frames per second", self.record_fps)
        job = self.record_job
        if job is None:
            if imgui.button("Record the path to video"):
                self._start_recording(path_name)
            return
        imgui.text_wrapped(job.progress)
        if imgui.button("Stop recording"):
            job.stop()

    def poll_recording(self) -> None:
        """Every frame, whichever panel shows: say how a finished recording ended."""
        job = self.record_job
        status = job.poll() if job is not None else None
        if status is not None:
            self.record_job = None
            outcome = "recorded" if status == 0 else "recording stopped" if status == 130 else "recording failed"
            self.editor.messages.append(f"{outcome}: {job.progress}")

    def _start_recording(self, path_name: str) -> None:
        editor = self.editor
        folder = editor.path.parent if editor.path else Path.cwd()
        try:
            self.record_job = RecordJob(
                dataclasses.replace(editor.scene, camera=editor.camera),
                folder,
                path_name,
                Path(self.record_out),
                *self.record_size,
                self.record_fps,
            )
        except (OSError, SceneError, ValueError) as error:
            editor.messages.append(f"could not start recording: {error}")
            return
        editor.messages.append(f"recording {path_name} to {self.record_out} (in the background)")

    def close(self) -> None:
        """Stop a recording still running: the frames so far stay a playable video."""
        if self.record_job is not None:
            self.record_job.stop()

    # --- Statistics -----------------------------------------------------------------------------------------
    def statistics(self) -> None:
        editor, shown = self.editor, self.editor.last_stats
        if shown is None:
            return
        frame, plan, kinds = shown.frame, shown.frame.plan, shown.frame.plan.clouds_by_kind
        ms = shown.viewport_ms
        imgui.text(
            f"{ms:6.1f} ms ({1000.0 / max(ms, 1e-3):5.1f} fps)  clouds {frame.cloud_ms:.1f}  "
            f"impostor updates {frame.impostor_update_ms:.1f}  world {frame.world_ms:.1f}"
        )
        if shown.picture_reused:
            imgui.text("picture kept: nothing changed since it was drawn (clouds, updates, world: that frame's)")
        if shown.relighting:
            imgui.text(
                f"relighting in the background; shown meanwhile: {shown.shown_illumination} light"
                f" at {shown.shown_time_of_day:.2f} h"
            )
        imgui.text(
            f"particles drawn {frame.particles_drawn}, rendered to impostors {frame.particles_to_impostors}, "
            f"as point sprites {frame.particles_as_points}"
        )
        imgui.text(
            f"impostors drawn {plan.impostors_drawn}, regenerated {shown.impostors_regenerated} "
            f"(total {self.viewport.regenerations_total}), postponed {plan.regenerations_postponed}, "
            f"ring segments built {plan.ring_segments_built}"
        )
        imgui.text(
            f"clouds: full {kinds['full']}, crossfade {kinds['crossfade']}, impostor {kinds['impostor']}, "
            f"inside {kinds['inside']}, ring {kinds['ring']}, culled {kinds['culled']}"
        )
        imgui.text(
            f"units {plan.units} ({plan.units_grouped} of interpenetrating clouds); predicted "
            f"{plan.predicted_ms:.1f} ms against {frame.impostor_update_ms + frame.cloud_ms:.1f} "
            f"measured; largest error drawn {plan.accepted_error_tolerances:.2f} x the tolerance "
            f"({plan.tolerance_deg:.3f} deg)"
        )
        imgui.text(
            f"objects in clouds {plan.objects_in_clouds}: layers drawn {plan.layers_drawn}, "
            f"rebuilt {plan.layers_rebuilt}"
        )
        imgui.text(f"texture memory {frame.texture_bytes / 2**20:.1f} MiB")
        _, self.viewport.measure_overdraw = imgui.checkbox("Measure overdraw", self.viewport.measure_overdraw)
        imgui.same_line()
        _, self.viewport.heat_map = imgui.checkbox("Overdraw heat map", self.viewport.heat_map)
        if frame.overdraw is not None:
            overdraw = frame.overdraw
            imgui.text(f"overdraw mean {overdraw.mean:.1f}, max {overdraw.max:.0f}, analytic {overdraw.analytic:.1f}")
        history = list(editor.frame_times)
        if implot.begin_plot("Frame time (ms)", imgui.ImVec2(-1, 180)):
            frames = np.arange(len(history), dtype=np.float64)
            implot.setup_axes("frame", "ms", implot.AxisFlags_.auto_fit, 0)
            # scaled to the frames' 95th percentile: the start's shading (seconds) would flatten the rest
            typical = np.percentile([s.viewport_ms for s in history], 95) if history else 1.0
            implot.setup_axis_limits(implot.ImAxis_.y1, 0.0, 1.25 * max(typical, 1.0), implot.Cond_.always)
            for label, times in (
                ("frame", [s.viewport_ms for s in history]),
                ("cloud pass", [s.frame.cloud_ms for s in history]),
                ("impostor updates", [s.frame.impostor_update_ms for s in history]),
                ("world", [s.frame.world_ms for s in history]),
            ):
                implot.plot_line(label, frames, np.array(times, dtype=np.float64))
            implot.end_plot()


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


#: settings drawn by one widget of their own (the panel leaves their fellows, such as the largest size, out)
_COMPOUND_WIDGETS = {"ring_radius": _ring_widgets, "impostor_min_size": _impostor_size_widgets}
