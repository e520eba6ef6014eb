"""What the editor holds between frames: the scene and its history, the file, settings, the tools, the
camera path playing, messages (no GL, no GUI).

The panels read and change an `Editor`; the viewport asks the engine to draw
`editor.scene` with `editor.settings`.  Saves are atomic (`save_scene`); a
recovery copy is written beside the scene at most a minute after an unsaved
edit, so a crash loses at most a minute of work: the next `open` says the copy
is there and `recover` loads it.
"""

from __future__ import annotations

import dataclasses
import math
import os
import shutil
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from cloudcore.maths.paths import camera_on_path
from cloudcore.model.errors import SceneError
from cloudcore.model.particle_files import particles_folder
from cloudcore.model.scene import Camera, Lighting, Scene, Shading
from cloudcore.model.settings import RenderSettings
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.editing import (
    History,
    delete_cloud,
    delete_particles,
    new_camera_path,
    with_camera_key,
    with_camera_key_time,
    with_camera_path,
    without_camera_key,
)
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.interop.camera_paths import read_camera_path, write_camera_path
from cloudcore.scenes.interop.vdb_clouds import DEFAULT_PARTICLES, export_vdb, free_name, import_vdb_clouds
from cloudcore.scenes.limits import scene_limit_problems
from cloudcore.stats.frame_stats import FrameStats

AUTOSAVE_SECONDS = 60.0
#: the editor's frame budget (`RenderSettings.frame_budget_ms`), the LOD panel's starting value: a new
#: time of day or shading makes every impostor stale, and remaking all of the default view's in one frame
#: would hold the window for several frames' time; within the budget they follow over a few frames (dragging the
#: time of day on the default scene, the smaller budgets gave more relit pictures a second and shorter
#: longest frames: docs/performance.md, "Live time of day")
EDITOR_FRAME_BUDGET_MS = 30.0
RECENT_LIMIT = 8
#: the Camera panel's scene clock runs to at least this many seconds under wind: ten minutes of drifting clouds
WIND_CLOCK_S = 600.0
#: what a left press in the viewport does, by name: (key, label)
TOOLS = (("place", "Place"), ("brush", "Brush"), ("move_cloud", "Move cloud"), ("move_particle", "Move particle"))


#: the folder of the built-in scenes, package data: an artist's unsaved edits to one are kept elsewhere
BUILT_IN_SCENES = DEFAULT_SCENE.parent


def recovery_path(path: Path) -> Path:
    """Where the unsaved edits to the scene at `path` are kept: beside it, but for the built-in scenes, which are
    the package's own files (in site-packages where installed): under the user's state directory,
    `$XDG_STATE_HOME/cloudview/recovery` (`~/.local/state` where that is unset)."""
    path = Path(path)
    if path.resolve().is_relative_to(BUILT_IN_SCENES.resolve()):
        state = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
        return Path(state) / "cloudview" / "recovery" / f"{path.stem}.recovery.toml"
    return path.with_name(f"{path.stem}.recovery.toml")


def discard_recovery(path: Path) -> None:
    """Delete the recovery copy of the scene at `path`, with the particle files it owns."""
    recovery = recovery_path(path)
    recovery.unlink(missing_ok=True)
    shutil.rmtree(recovery.with_name(particles_folder(recovery)), ignore_errors=True)


@dataclass(frozen=True)
class ShownFrame:
    """One window frame of the viewport: the frame whose picture it shows, and what the editor showed."""

    frame: FrameStats  # of the frame that drew the picture (an earlier one when `picture_reused`)
    picture_reused: bool  # nothing it is drawn from changed, or a newer light is on its way: not redrawn
    relighting: bool  # the light pass is running in the background
    shown_time_of_day: float
    shown_illumination: str  # the shading method of the light shown (`cloudcore.light.relighting`)
    frame_start_s: float  # perf_counter at the window frame's start
    viewport_ms: float
    viewport_width: int
    viewport_height: int

    @property
    def impostors_regenerated(self) -> int:
        return 0 if self.picture_reused else self.frame.plan.impostors_regenerated

    def as_dict(self) -> dict:
        """The flat form (the frame's `as_dict` and the editor's own), for `python -m app --frame-stats`."""
        shown = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "frame"}
        return self.frame.as_dict() | shown | {"impostors_regenerated": self.impostors_regenerated}


class Editor:
    def __init__(self, scene: Scene, path: Path | None):
        self.history = History(scene)
        self.path = path
        self.saved_scene = scene
        self.settings = RenderSettings(frame_budget_ms=EDITOR_FRAME_BUDGET_MS)
        #: while a lighting or shading slider is dragged, the (shading, lighting) it would give: the viewport
        #: shows them live; the history gets the value once, on release.  None: the scene's own
        self.dragged_look: tuple[Shading, Lighting] | None = None
        self.camera: Camera = scene.camera
        #: the scene clock the objects move by (seconds, in their path keys' time)
        self.scene_time_s = 0.0
        self.selected_cloud = 0 if scene.clouds else None
        self.tool = "place"
        #: where Place and Brush put particles: on the selected cloud's particles, or on the altitude plane
        self.on_cloud_surface = False
        self.placement_altitude = 1000.0
        self.particle_radius = 60.0
        self.brush_radius = 250.0
        self.brush_rate = 40.0  # particles per second held
        self.brush_erases = False
        self._strokes = 0
        self._picked: tuple[int, int, Scene] | None = None  # (cloud, particle, the scene they index)
        self.camera_path_name: str | None = scene.camera_paths[0].name if scene.camera_paths else None
        self.path_time_s = 0.0
        self.playing = False
        self.messages: deque[str] = deque(maxlen=6)
        self.recent: list[Path] = [path] if path else []
        self.frame_times: deque[ShownFrame] = deque(maxlen=240)
        self.last_stats: ShownFrame | None = None
        self._last_recovery = time.monotonic()
        self._recovered_scene: Scene | None = None  # the scene the recovery copy last written holds

    @property
    def scene_duration_s(self) -> float:
        """The last key time of any object path and the end of a change of weather (0 for a scene with neither),
        and under wind at least `WIND_CLOCK_S`: the clouds move as long as the clock runs."""
        paths = max((float(o.path[-1, 0]) for o in self.scene.objects if o.path is not None), default=0.0)
        weather = self.scene.weather
        if weather is not None and weather.to is not None:
            paths = max(paths, weather.start_s + weather.duration_s)
        return paths if self.scene.wind is None else max(paths, WIND_CLOCK_S)

    @classmethod
    def open(cls, path: Path) -> Editor:
        editor = cls(load_scene(path), path)
        editor._mention_recovery()
        return editor

    def _mention_recovery(self) -> None:
        if self.path is not None and recovery_path(self.path).exists():
            self.messages.append(
                f"a recovery file of unsaved edits exists: {recovery_path(self.path)} "
                "(Scene panel: Recover unsaved edits)"
            )

    def recover(self) -> bool:
        """Load the recovery copy of the open scene as one undoable edit.

        The scene keeps its path, so Save writes the recovered edits over the last
        save (and discards the copy); undo returns to the scene as last saved.
        """
        recovery = recovery_path(self.path) if self.path is not None else None
        if recovery is None or not recovery.exists():
            self.messages.append("there is no recovery file to load")
            return False
        try:
            scene = load_scene(recovery)
        except SceneError as error:
            self.messages.append(f"could not recover: {error}")
            return False
        self.edit(scene)
        self.camera = scene.camera
        self.messages.append(f"recovered the unsaved edits in {recovery}; save to keep them")
        return True

    @property
    def scene(self) -> Scene:
        return self.history.current

    @property
    def dirty(self) -> bool:
        return self.scene is not self.saved_scene

    @property
    def look(self) -> tuple[Shading, Lighting]:
        """The (shading, lighting) to show: a dragged slider's, else the scene's."""
        return self.dragged_look if self.dragged_look is not None else (self.scene.shading, self.scene.lighting)

    @property
    def time_of_day(self) -> float | None:
        return self.scene.lighting.time_of_day

    def edit(self, scene: Scene) -> bool:
        """Apply an edit (undoable).  One the renderer could not draw (`cloudcore.scenes.limits`, the
        limits the scene loader checks too) is refused with a message; the scene stays as it was."""
        problems = scene_limit_problems(scene, unchanged=self.scene)
        if problems:
            self.messages.append("not applied: {}: {}".format(*problems[0]))
            return False
        self.history.apply(scene)
        self._keep_selection()
        return True

    def _keep_selection(self) -> None:
        """The selected cloud stays one the scene has: an edit, an undo or a redo may have removed it."""
        clouds = len(self.scene.clouds)
        if not clouds:
            self.selected_cloud = None
        elif self.selected_cloud is None:
            self.selected_cloud = 0
        elif self.selected_cloud >= clouds:
            self.selected_cloud = clouds - 1

    def change(self, make: Callable[[], Scene]) -> bool:
        """Build an edit of the current scene with `make` and apply it; an edit the editing
        functions refuse (ValueError: a radius of 0, a non-finite point) becomes a message."""
        try:
            scene = make()
        except ValueError as error:
            self.messages.append(f"not applied: {error}")
            return False
        return self.edit(scene)

    def begin_gesture(self) -> None:
        """Edits until `end_gesture` (a brush stroke, a drag) undo as one."""
        self.history.begin_gesture()

    def end_gesture(self) -> None:
        self.history.end_gesture()

    def next_stroke_seed(self) -> int:
        """A new seed for each brush stroke: strokes differ, and a session replays the same."""
        self._strokes += 1
        return self._strokes

    def pick(self, cloud: int, particle: int) -> None:
        """Make a particle the one Delete removes (until the scene changes otherwise)."""
        self._picked = (cloud, particle, self.scene)

    @property
    def picked_particle(self) -> tuple[int, int] | None:
        """(cloud, particle) picked in the scene shown now; any other edit, undo included, forgets it."""
        if self._picked is None or self._picked[2] is not self.scene:
            return None
        return self._picked[:2]

    def delete_selection(self) -> None:
        """Delete the picked particle, or else the selected cloud (undoable)."""
        picked = self.picked_particle
        if picked is not None:
            self.edit(delete_particles(self.scene, picked[0], [picked[1]]))
            self.messages.append(f"deleted particle {picked[1]} of {self.scene.clouds[picked[0]].name}")
        elif self.selected_cloud is not None:
            name = self.scene.clouds[self.selected_cloud].name
            self.edit(delete_cloud(self.scene, self.selected_cloud))
            self.messages.append(f"deleted cloud {name}")
        else:
            self.messages.append("nothing to delete: pick a particle (Move particle) or select a cloud")

    def show_path_time(self, seconds: float) -> None:
        """Put the camera (and the scene clock) where the chosen camera path is `seconds` from its start."""
        if not math.isfinite(seconds):
            self.messages.append(f"a time along the path must be finite, got {seconds}")
            return
        path = self.scene.camera_path(self.camera_path_name)
        self.path_time_s = min(max(float(seconds), 0.0), path.duration)
        self.camera = camera_on_path(path, self.path_time_s, self.camera.fov_y_deg)
        self.scene_time_s = float(path.keys[0, 0]) + self.path_time_s

    def play(self) -> None:
        if self.camera_path_name is None:
            self.messages.append("the scene has no camera path to play")
            return
        if self.path_time_s >= self.scene.camera_path(self.camera_path_name).duration:
            self.path_time_s = 0.0  # played to the end: play again from the start
        self.playing = True

    def advance_playback(self, seconds: float) -> None:
        """Move along the playing path by `seconds` of wall time; it stops at the path's end."""
        if not self.playing:
            return
        if self.camera_path_name not in {p.name for p in self.scene.camera_paths}:
            self.playing = False  # the scene changed under it (opened, undone)
            return
        self.show_path_time(self.path_time_s + seconds)
        self.playing = self.path_time_s < self.scene.camera_path(self.camera_path_name).duration

    def set_time_of_day(self, hours: float) -> None:
        self.edit(
            dataclasses.replace(self.scene, lighting=dataclasses.replace(self.scene.lighting, time_of_day=float(hours)))
        )

    def undo(self) -> None:
        if not self.history.undo():
            self.messages.append("nothing to undo")
        self._keep_selection()

    def redo(self) -> None:
        if not self.history.redo():
            self.messages.append("nothing to redo")
        self._keep_selection()

    def open_file(self, path: Path) -> bool:
        """Open another scene; a bad file leaves the current scene as it was and says why.  Unsaved edits are
        written to the recovery copy first (Recover brings them back when their scene is opened again); where
        they cannot be, the scene stays open."""
        try:
            scene = load_scene(path)
        except SceneError as error:
            self.messages.append(f"could not open: {error}")
            return False
        if self.dirty and not self._keep_unsaved_edits():
            return False
        self.history.reset(scene)
        self.saved_scene, self.path, self.camera = scene, Path(path), scene.camera
        self.selected_cloud = 0 if scene.clouds else None
        self.camera_path_name = scene.camera_paths[0].name if scene.camera_paths else None
        self.path_time_s, self.playing = 0.0, False
        self._remember(Path(path))
        self.messages.append(f"opened {path}")
        self._mention_recovery()
        return True

    def import_vdb(self, path: Path, max_particles: int = DEFAULT_PARTICLES) -> bool:
        """Add a cloud for each density grid of the OpenVDB file at `path`, as one undoable edit; a file that
        cannot be imported leaves the scene as it was and says why."""
        try:
            imported = import_vdb_clouds(path, max_particles, taken_names=[cloud.name for cloud in self.scene.clouds])
        except SceneError as error:
            self.messages.append(f"could not import: {error}")
            return False
        clouds = tuple(item.cloud for item in imported)
        if not self.edit(dataclasses.replace(self.scene, clouds=self.scene.clouds + clouds)):
            return False
        self.selected_cloud = len(self.scene.clouds) - 1
        errors = ", ".join(f"{item.cloud.name} L1 {100 * item.fit.relative_l1:.0f}%" for item in imported)
        self.messages.append(f"imported {len(clouds)} cloud(s) from {Path(path).name} (density error {errors})")
        return True

    def export_vdb(self, path: Path) -> bool:
        """Write the scene's clouds to the OpenVDB file at `path`, one extinction grid a cloud."""
        try:
            grids = export_vdb(self.scene, path)
        except (OSError, SceneError) as error:
            self.messages.append(f"could not export {path}: {error}")
            return False
        self.messages.append(f"exported {len(grids)} grid(s) to {path}")
        return True

    def _path_index(self) -> int | None:
        """The index of the chosen camera path in the scene, or None where it has none of that name."""
        names = [path.name for path in self.scene.camera_paths]
        return names.index(self.camera_path_name) if self.camera_path_name in names else None

    def add_camera_key(self, time_s: float) -> bool:
        """Add a key at `time_s` looking as the view does now to the chosen camera path (undoable); with no
        path, a new one from the scene's camera at time 0 to the view."""
        index = self._path_index()
        if index is None:
            name = free_name("path", [path.name for path in self.scene.camera_paths])
            if not self.change(lambda: new_camera_path(self.scene, name, time_s, self.camera)):
                return False
            self.camera_path_name, self.path_time_s, self.playing = name, 0.0, False
            self.messages.append(f"new camera path {name}: the scene's camera, then the view at {time_s:g} s")
            return True
        if not self.change(lambda: with_camera_key(self.scene, index, time_s, self.camera)):
            return False
        self.messages.append(f"added a key at {time_s:g} s to {self.camera_path_name}")
        return True

    def move_camera_key(self, key_index: int, time_s: float) -> bool:
        """Move key `key_index` of the chosen camera path to `time_s` (undoable; not past its neighbours)."""
        index = self._path_index()
        return index is not None and self.change(lambda: with_camera_key_time(self.scene, index, key_index, time_s))

    def delete_camera_key(self, key_index: int) -> bool:
        """Delete key `key_index` of the chosen camera path (undoable; a path keeps two keys at least)."""
        index = self._path_index()
        return index is not None and self.change(lambda: without_camera_key(self.scene, index, key_index))

    def import_camera_path(self, path: Path) -> bool:
        """Add the camera path of a glTF or CSV file as one undoable edit and choose it; a file that cannot be
        imported leaves the scene as it was and says why."""
        try:
            imported = read_camera_path(path)
        except SceneError as error:
            self.messages.append(f"could not import: {error}")
            return False
        name = free_name(imported.name, [p.name for p in self.scene.camera_paths])
        if not self.edit(with_camera_path(self.scene, dataclasses.replace(imported, name=name))):
            return False
        self.camera_path_name, self.path_time_s, self.playing = name, 0.0, False
        self.messages.append(f"imported camera path {name} ({len(imported.keys)} keys) from {Path(path).name}")
        return True

    def export_camera_path(self, path: Path) -> bool:
        """Write the chosen camera path to a glTF (.gltf, .glb) or CSV file."""
        index = self._path_index()
        if index is None:
            self.messages.append("the scene has no camera path to export")
            return False
        try:
            write_camera_path(path, self.scene.camera_paths[index], self.camera.fov_y_deg)
        except (OSError, SceneError) as error:
            self.messages.append(f"could not export {path}: {error}")
            return False
        self.messages.append(f"exported camera path {self.camera_path_name} to {path}")
        return True

    def _keep_unsaved_edits(self) -> bool:
        """Write the unsaved edits to the recovery copy before another scene replaces them; False (and why)
        where they cannot be kept."""
        if self.path is None:
            self.messages.append("not opened: the scene's unsaved edits have no file to be kept beside; Save as first")
            return False
        if self.scene is not self._recovered_scene and not self._write_recovery():
            self.messages.append("not opened: save the unsaved edits first, or undo them")
            return False
        self.messages.append(
            f"the unsaved edits to {self.path.name} are kept in {recovery_path(self.path)}: "
            "open it again and Recover them"
        )
        return True

    def save(self, path: Path | None = None) -> bool:
        target = Path(path) if path is not None else self.path
        if target is None:
            self.messages.append("choose a file name to save to (Save as)")
            return False
        try:
            scene = save_scene(dataclasses.replace(self.scene, camera=self.camera), target)
        except (OSError, SceneError, ValueError) as error:
            self.messages.append(f"could not save {target}: {error}")
            return False
        # the scene as saved (its camera, the particle files it names) is the current one, not an edit
        self.history.current = scene
        self.saved_scene, self.path = scene, target
        discard_recovery(target)
        self._remember(target)
        self.messages.append(f"saved {target}")
        return True

    def autosave(self, now: float | None = None) -> bool:
        """Write the recovery copy when there are unsaved edits it lacks and a minute has passed since the last.

        `now` is `time.monotonic()`'s clock.  The copy is a scene of its own, with its
        own particle files (`save_scene`), so writing it never touches the last save.
        """
        now = time.monotonic() if now is None else now
        if (
            not self.dirty
            or self.path is None
            or self.scene is self._recovered_scene
            or now - self._last_recovery < AUTOSAVE_SECONDS
        ):
            return False
        self._last_recovery = now
        return self._write_recovery()

    def _write_recovery(self) -> bool:
        try:
            recovery = recovery_path(self.path)
            recovery.parent.mkdir(parents=True, exist_ok=True)
            save_scene(dataclasses.replace(self.scene, camera=self.camera), recovery)
        except (OSError, SceneError, ValueError) as error:
            self.messages.append(f"could not write the recovery file: {error}")
            return False
        self._recovered_scene = self.scene
        return True

    def record_frame(self, stats: ShownFrame) -> None:
        self.last_stats = stats
        self.frame_times.append(stats)

    def _remember(self, path: Path) -> None:
        self.recent = [path] + [p for p in self.recent if p != path][: RECENT_LIMIT - 1]
