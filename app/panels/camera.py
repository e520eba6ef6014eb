"""The Camera panel: the eye, orbiting, scene time, camera paths (their keys edited, imported and exported) and
recording one to video."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from imgui_bundle import imgui

from app.editor import Editor
from app.panels.widgets import bounded_slider
from app.record_job import RecordJob
from app.viewport import Viewport
from cloudcore.model.errors import SceneError
from cloudcore.world.navigation import orbited


class CameraPanel:
    def __init__(self, editor: Editor, viewport: Viewport):
        self.editor, self.viewport = editor, viewport
        self.orbit_step_deg = 1.0
        # recording the chosen camera path
        self.record_out = ""
        self.record_size = [640, 480]
        self.record_fps = 30.0
        self.record_job: RecordJob | None = None
        # editing the chosen path's keys: the key picked in the list, the time typed for a key
        self.selected_key = 0
        self.key_time_s = 2.0
        self.path_file_field = ""

    def draw(self) -> None:
        editor = self.editor
        camera = editor.camera
        imgui.text("eye " + ", ".join(f"{v:.0f}" for v in camera.position))
        changed, fov = bounded_slider("Field of view", camera.fov_y_deg, 5.0, 120.0)
        if changed:
            editor.camera = dataclasses.replace(camera, fov_y_deg=fov)
        _, self.viewport.fly_speed = bounded_slider("Fly speed (m/s)", self.viewport.fly_speed, 10.0, 3000.0)
        _, self.orbit_step_deg = bounded_slider("Orbit step (deg)", self.orbit_step_deg, 0.01, 10.0)
        if imgui.button("Orbit left"):
            editor.camera = orbited(editor.camera, -self.orbit_step_deg)
        imgui.same_line()
        if imgui.button("Orbit right"):
            editor.camera = orbited(editor.camera, self.orbit_step_deg)
        if imgui.button("Reset to the scene's camera"):
            editor.camera = editor.scene.camera
        if editor.scene_duration_s > 0.0:
            _, editor.scene_time_s = bounded_slider("Scene time (s)", editor.scene_time_s, 0.0, editor.scene_duration_s)
        self._camera_paths()

    def _camera_paths(self) -> None:
        editor = self.editor
        imgui.separator_text("Camera path")
        self._path_files()
        names = [p.name for p in editor.scene.camera_paths]
        if not names:
            imgui.text("the scene has no camera paths")
            self._key_time()
            self._add_key_at_the_view()
            return
        current = names.index(editor.camera_path_name) if editor.camera_path_name in names else 0
        changed, current = imgui.combo("Path", current, names)
        if changed or editor.camera_path_name not in names:
            editor.camera_path_name, editor.path_time_s, editor.playing = names[current], 0.0, False
            self.selected_key = 0
        if imgui.button("Play"):
            editor.play()
        imgui.same_line()
        if imgui.button("Pause"):
            editor.playing = False
        duration = editor.scene.camera_path(editor.camera_path_name).duration
        changed, seconds = bounded_slider("Path time (s)", editor.path_time_s, 0.0, duration, "%.2f")
        if changed:
            editor.playing = False
            editor.show_path_time(seconds)
        self._keys()
        self._recording(editor.camera_path_name)

    def _path_files(self) -> None:
        """Import a camera path from a glTF or CSV file, or export the chosen one to one."""
        _, self.path_file_field = imgui.input_text("Path file", self.path_file_field)
        imgui.set_item_tooltip("a camera path's file: glTF camera animation (.gltf, .glb) or CSV (t,px,py,pz,lx,ly,lz)")
        if imgui.button("Import path..."):
            self.editor.import_camera_path(Path(self.path_file_field))
        imgui.set_item_tooltip("add the file's camera path to the scene, and choose it")
        imgui.same_line()
        if imgui.button("Export path..."):
            self.editor.export_camera_path(Path(self.path_file_field))
        imgui.set_item_tooltip("write the chosen camera path to the file")

    def _keys(self) -> None:
        """The chosen path's keys listed (a click shows a key's view); a key added at the view, moved to the
        typed time, or deleted, each one undoable edit."""
        editor = self.editor
        keys = editor.scene.camera_path(editor.camera_path_name).keys
        self.selected_key = min(self.selected_key, len(keys) - 1)
        imgui.text(f"Keys ({len(keys)}): time (s), eye")
        if imgui.begin_list_box("##keys", imgui.ImVec2(-1.0, 5.5 * imgui.get_text_line_height_with_spacing())):
            # the rows in sight alone: an imported path may hold a key a frame, 10,000 of them
            clipper = imgui.ListClipper()
            clipper.begin(len(keys))
            while clipper.step():
                for index in range(clipper.display_start, clipper.display_end):
                    key = keys[index]
                    label = f"{index}: {key[0]:.2f}  {key[1]:.0f}, {key[2]:.0f}, {key[3]:.0f}###key{index}"
                    if imgui.selectable(label, index == self.selected_key)[0]:
                        self.selected_key, self.key_time_s = index, float(key[0])
                        editor.playing = False
                        editor.show_path_time(float(key[0] - keys[0, 0]))
            imgui.end_list_box()
        self._key_time()
        self._add_key_at_the_view()
        imgui.same_line()
        if imgui.button("Move key"):
            editor.move_camera_key(self.selected_key, self.key_time_s)
        imgui.set_item_tooltip("move the key picked in the list to the key time")
        imgui.same_line()
        if imgui.button("Delete key"):
            editor.delete_camera_key(self.selected_key)
        imgui.set_item_tooltip("delete the key picked in the list")

    def _key_time(self) -> None:
        _, self.key_time_s = imgui.input_float("Key time (s)", self.key_time_s, 0.5, 5.0, "%.2f")

    def _add_key_at_the_view(self) -> None:
        if imgui.button("Add key at the view"):
            self.editor.add_camera_key(self.key_time_s)
        imgui.set_item_tooltip(
            "a key at the key time looking as the view does now (with no path: a new one from the scene's camera)"
        )

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
