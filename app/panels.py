"""The editor's panels: each reads and edits the `Editor` and calls the engine; no rendering maths here."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
from imgui_bundle import imgui, implot

from app.editor import Editor
from app.viewport import Viewport
from cloudcore.editing import add_cloud, delete_cloud, replace_cloud
from cloudcore.navigation import orbited
from cloudcore.phase import PHASE_NAMES
from cloudcore.settings import MODES


class Panels:
    def __init__(self, editor: Editor, viewport: Viewport):
        self.editor, self.viewport = editor, viewport
        self.file_field = str(editor.path or "")
        self.orbit_step_deg = 1.0
        self._dragging: dict[str, float] = {}

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
        for path in editor.recent[1:]:
            if imgui.small_button(f"recent: {path}"):
                self.file_field = str(path)
                editor.open_file(path)
        imgui.separator()
        for message in reversed(editor.messages):
            imgui.text_wrapped(message)

    # --- Clouds and particle placement -----------------------------------------------------------------
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
        imgui.separator()
        imgui.text("Click in the viewport to place a particle")
        _, editor.placement_altitude = imgui.slider_float("Altitude (m)", editor.placement_altitude, 0.0, 5000.0)
        _, editor.particle_radius = imgui.slider_float("Particle radius (m)", editor.particle_radius, 1.0, 500.0)
        if editor.selected_cloud is not None:
            cloud = editor.scene.clouds[editor.selected_cloud]
            tau = scene.shading.optical_depth if cloud.optical_depth is None else cloud.optical_depth
            tau = self._slider_on_release("Cloud optical depth", tau, 0.0, 50.0)
            if tau is not None:
                editor.edit(replace_cloud(scene, editor.selected_cloud,
                                          dataclasses.replace(cloud, optical_depth=float(tau))))

    # --- Lighting -------------------------------------------------------------------------------------------
    def lighting(self) -> None:
        editor = self.editor
        scene = editor.scene
        hours = editor.time_of_day if editor.time_of_day is not None else 12.0
        hours = self._slider_on_release("Time of day", hours, 0.0, 24.0, "%.2f h")
        if hours is not None:
            editor.set_time_of_day(hours)
        shading = scene.shading
        changes = {"albedo": self._slider_on_release("Albedo", shading.albedo, 0.0, 1.0),
                   "optical_depth": self._slider_on_release("Optical depth", shading.optical_depth, 0.0, 50.0),
                   "g": self._slider_on_release("g", shading.g, -0.99, 0.99)}
        changed_phase, phase_index = imgui.combo("Phase function", PHASE_NAMES.index(shading.phase),
                                                 list(PHASE_NAMES))
        changes = {key: value for key, value in changes.items() if value is not None}
        if changed_phase:
            changes["phase"] = PHASE_NAMES[phase_index]
        if changes:
            editor.edit(dataclasses.replace(scene, shading=dataclasses.replace(shading, **changes)))

    # --- LOD ------------------------------------------------------------------------------------------------
    def lod(self) -> None:
        editor = self.editor
        settings = editor.settings
        changed_mode, mode = imgui.combo("Mode", MODES.index(settings.mode), list(MODES))
        changed_tol, tolerance = imgui.slider_float("Tolerance (deg)", settings.tolerance_deg, 0.0, 5.0, "%.3f")
        ring_on = math.isfinite(settings.ring_radius)
        changed_ring_on, ring_on = imgui.checkbox("Impostor ring", ring_on)
        radius = settings.ring_radius if math.isfinite(settings.ring_radius) else 4000.0
        changed_radius, radius = imgui.slider_float("Ring radius (m)", radius, 0.0, 20000.0, "%.0f")
        changed_fade, fades = imgui.slider_float2("Fade (radii)", [settings.fade_start_radii,
                                                                    settings.fade_end_radii], 1.0, 10.0)
        sizes = [int(math.log2(settings.impostor_min_size)), int(math.log2(settings.impostor_max_size))]
        changed_sizes, sizes = imgui.slider_int2("Impostor size (log2)", sizes, 3, 12)
        if changed_mode or changed_tol or changed_ring_on or changed_radius or changed_fade or changed_sizes:
            try:
                editor.settings = dataclasses.replace(
                    settings, mode=MODES[mode], tolerance_deg=tolerance,
                    ring_radius=radius if ring_on else math.inf,
                    fade_start_radii=min(fades), fade_end_radii=max(fades),
                    impostor_min_size=2 ** min(sizes), impostor_max_size=2 ** max(sizes))
            except ValueError as error:
                editor.messages.append(str(error))

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
            _, editor.scene_time_s = imgui.slider_float("Scene time (s)", editor.scene_time_s, 0.0,
                                                        editor.scene_duration_s)

    # --- Statistics -----------------------------------------------------------------------------------------
    def statistics(self) -> None:
        editor, stats = self.editor, self.editor.last_stats
        if not stats:
            return
        frame = stats.get("viewport_ms", stats["frame_ms"])
        imgui.text(f"{frame:6.1f} ms ({1000.0 / max(frame, 1e-3):5.1f} fps)  clouds {stats['cloud_ms']:.1f}  "
                   f"impostor updates {stats['impostor_update_ms']:.1f}  world {stats['world_ms']:.1f}")
        imgui.text(f"particles drawn {stats['particles_drawn']}, rendered to impostors "
                   f"{stats['particles_to_impostors']}")
        imgui.text(f"impostors drawn {stats['impostors_drawn']}, regenerated {stats['impostors_regenerated']} "
                   f"(total {self.viewport.regenerations_total}), ring segments built {stats['ring_segments_built']}")
        imgui.text(f"clouds: full {stats['clouds_full']}, crossfade {stats['clouds_crossfade']}, impostor "
                   f"{stats['clouds_impostor']}, inside {stats['clouds_inside']}, ring {stats['clouds_ring']}, "
                   f"culled {stats['clouds_culled']}")
        imgui.text(f"objects in clouds {stats['objects_in_clouds']}: layers drawn {stats['layers_drawn']}, "
                   f"rebuilt {stats['layers_rebuilt']}")
        imgui.text(f"texture memory {stats['texture_bytes'] / 2**20:.1f} MiB")
        _, self.viewport.measure_overdraw = imgui.checkbox("Measure overdraw", self.viewport.measure_overdraw)
        if "overdraw_mean" in stats:
            imgui.text(f"overdraw mean {stats['overdraw_mean']:.1f}, max {stats['overdraw_max']:.0f}, "
                       f"analytic {stats['overdraw_analytic']:.1f}")
        history = list(editor.frame_times)
        if implot.begin_plot("Frame time (ms)", imgui.ImVec2(-1, 180)):
            frames = np.arange(len(history), dtype=np.float64)
            implot.setup_axes("frame", "ms", implot.AxisFlags_.auto_fit, implot.AxisFlags_.auto_fit)
            for key, label in (("viewport_ms", "frame"), ("cloud_ms", "cloud pass"),
                               ("impostor_update_ms", "impostor updates"), ("world_ms", "world")):
                implot.plot_line(label, frames, np.array([s.get(key, 0.0) for s in history], dtype=np.float64))
            implot.end_plot()
