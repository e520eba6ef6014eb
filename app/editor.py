"""What the editor holds between frames: the scene and its history, the file, settings, messages (no GL, no GUI).

The panels read and change an `Editor`; the viewport asks the engine to draw
`editor.scene` with `editor.settings`.  Saves are atomic (`save_scene`); a
recovery copy is written beside the scene at most a minute after an unsaved
edit, so a crash loses at most a minute of work.
"""

from __future__ import annotations

import dataclasses
import time
from collections import deque
from pathlib import Path

from cloudcore.editing import History
from cloudcore.errors import SceneError
from cloudcore.scene import Camera, Scene
from cloudcore.scenefile import load_scene, save_scene
from cloudcore.settings import RenderSettings

AUTOSAVE_SECONDS = 60.0
RECENT_LIMIT = 8


def recovery_path(path: Path) -> Path:
    return path.with_name(f"{path.stem}.recovery.toml")


class Editor:
    def __init__(self, scene: Scene, path: Path | None):
        self.history = History(scene)
        self.path = path
        self.saved_scene = scene
        self.settings = RenderSettings()
        self.camera: Camera = scene.camera
        #: the scene clock the objects move by (seconds, in their path keys' time)
        self.scene_time_s = 0.0
        self.selected_cloud = 0 if scene.clouds else None
        self.placement_altitude = 1000.0
        self.particle_radius = 60.0
        self.messages: deque[str] = deque(maxlen=6)
        self.recent: list[Path] = [path] if path else []
        self.frame_times: deque[dict] = deque(maxlen=240)
        self.last_stats: dict = {}
        self._last_recovery = time.monotonic()

    @property
    def scene_duration_s(self) -> float:
        """The last key time of any object path (0 for a scene with static objects only)."""
        return max((float(o.path[-1, 0]) for o in self.scene.objects if o.path is not None), default=0.0)

    @classmethod
    def open(cls, path: Path) -> "Editor":
        editor = cls(load_scene(path), path)
        if recovery_path(path).exists():
            editor.messages.append(f"a recovery file from an unsaved session exists: {recovery_path(path)}")
        return editor

    @property
    def scene(self) -> Scene:
        return self.history.current

    @property
    def dirty(self) -> bool:
        return self.scene is not self.saved_scene

    @property
    def time_of_day(self) -> float | None:
        return self.scene.lighting.time_of_day

    def edit(self, scene: Scene) -> None:
        """Apply an edit (undoable)."""
        self.history.apply(scene)
        if self.selected_cloud is not None and self.selected_cloud >= len(scene.clouds):
            self.selected_cloud = len(scene.clouds) - 1 if scene.clouds else None

    def set_time_of_day(self, hours: float) -> None:
        self.edit(dataclasses.replace(self.scene, lighting=dataclasses.replace(self.scene.lighting,
                                                                               time_of_day=float(hours))))

    def undo(self) -> None:
        if not self.history.undo():
            self.messages.append("nothing to undo")

    def redo(self) -> None:
        if not self.history.redo():
            self.messages.append("nothing to redo")

    def open_file(self, path: Path) -> bool:
        """Open another scene; a bad file leaves the current scene as it was and says why."""
        try:
            scene = load_scene(path)
        except SceneError as error:
            self.messages.append(f"could not open: {error}")
            return False
        self.history.reset(scene)
        self.saved_scene, self.path, self.camera = scene, Path(path), scene.camera
        self.selected_cloud = 0 if scene.clouds else None
        self._remember(Path(path))
        self.messages.append(f"opened {path}")
        return True

    def save(self, path: Path | None = None) -> bool:
        target = Path(path) if path is not None else self.path
        if target is None:
            self.messages.append("choose a file name to save to (Save as)")
            return False
        scene = dataclasses.replace(self.scene, camera=self.camera)
        try:
            save_scene(scene, target)
        except (OSError, SceneError, ValueError) as error:
            self.messages.append(f"could not save {target}: {error}")
            return False
        self.history.current = scene  # the saved camera is part of the scene now, not an edit
        self.saved_scene, self.path = scene, target
        recovery_path(target).unlink(missing_ok=True)
        self._remember(target)
        self.messages.append(f"saved {target}")
        return True

    def autosave(self, now: float | None = None) -> bool:
        """Write the recovery copy when there are unsaved edits and a minute has passed."""
        now = time.monotonic() if now is None else now
        if not self.dirty or self.path is None or now - self._last_recovery < AUTOSAVE_SECONDS:
            return False
        self._last_recovery = now
        try:
            save_scene(self.scene, recovery_path(self.path))
        except (OSError, SceneError, ValueError) as error:
            self.messages.append(f"could not write the recovery file: {error}")
            return False
        return True

    def record_frame(self, stats: dict) -> None:
        self.last_stats = stats
        self.frame_times.append(stats)

    def _remember(self, path: Path) -> None:
        self.recent = [path] + [p for p in self.recent if p != path][:RECENT_LIMIT - 1]
