"""Crashes lose nothing saved (issue 9): processes killed (SIGKILL) mid-save and mid-edit.

A child process saves, or edits with an `app.editor.Editor` under a simulated
clock, and is killed without warning: at every rename a save makes (the child
announces each one and waits before doing it), or after a random delay.  Then
the scene file must load as the old scene or the new one, whole, never a mix
of the two; the editor's recovery copy must hold the edits up to its last
autosave, at most a minute of edits behind; and the next `Editor.open` must
offer the copy, which `Editor.recover` loads.
"""

import dataclasses
import random
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from app.editor import AUTOSAVE_SECONDS, Editor, recovery_path
from cloudcore.model.particle_files import particles_folder
from cloudcore.model.scene import Camera, Cloud, Scene
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import INLINE_PARTICLE_LIMIT, load_scene, save_scene
from tests.conftest import ROOT

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL (POSIX)")

# Run in the child: os.replace made to print the file it is about to replace and wait, so the
# parent can kill the child between any two renames of a save.
ANNOUNCE_RENAMES = """
import os, time
from pathlib import Path

_replace = os.replace

def _announced_replace(source, destination):
    print("rename", Path(destination).name, flush=True)
    time.sleep(0.3)
    _replace(source, destination)

if ANNOUNCE:
    os.replace = _announced_replace
"""

SAVING_CHILD = (
    ANNOUNCE_RENAMES
    + """
import itertools, sys
from cloudcore.scenes.files import load_scene, save_scene

old, new = (load_scene(path) for path in sys.argv[1:3])
target = sys.argv[3]
print("ready", flush=True)
for scene in itertools.cycle([new, old]) if LOOP else [new]:
    save_scene(scene, target)
print("done", flush=True)
"""
)

EDITING_CHILD = (
    ANNOUNCE_RENAMES
    + """
import dataclasses, itertools, sys, time
import numpy as np
from app.editor import Editor

editor = Editor.open(Path(sys.argv[1]))
start = time.monotonic()  # the simulated clock: edit i is made EDIT_SECONDS * i after the start
for i in itertools.count(1):
    cloud = editor.scene.clouds[0]
    grown = dataclasses.replace(cloud, particles=np.vstack([cloud.particles, [[float(i), 0.0, 0.0, 10.0]]]))
    editor.edit(dataclasses.replace(editor.scene, description=f"edit {i}", clouds=(grown, *editor.scene.clouds[1:])))
    print("edit", i, flush=True)
    if editor.autosave(now=start + EDIT_SECONDS * i):
        print("autosaved", i, flush=True)
    time.sleep(0.005)  # an artist's pace, which also keeps the undo history's memory small
"""
)

#: simulated seconds between two edits of the editing child: an autosave every sixth edit
EDIT_SECONDS = 10.0


def large_scene(description: str, seed: int) -> Scene:
    """Three clouds in particle files (the last the same in every version) and one inline."""
    rng = np.random.default_rng(seed)
    clouds = [
        Cloud(f"cumulus {i}", np.column_stack([rng.normal(size=(20_000, 3)) * 500, rng.uniform(20, 60, 20_000)]))
        for i in range(2)
    ]
    clouds.append(Cloud("steady", np.column_stack([np.arange(3000.0).repeat(3).reshape(-1, 3), np.ones(3000)])))
    clouds.append(
        Cloud("wisp", np.column_stack([rng.normal(size=(INLINE_PARTICLE_LIMIT, 3)), np.ones(INLINE_PARTICLE_LIMIT)]))
    )
    return Scene(camera=Camera(fov_y_deg=40.0 + seed), clouds=tuple(clouds), description=description)


def content(scene: Scene) -> Scene:
    """The scene without where its particles were stored: what a reader of the scene sees."""
    return dataclasses.replace(scene, clouds=tuple(dataclasses.replace(c, particles_file=None) for c in scene.clouds))


class Child:
    """A Python child process running `code` with `constants` defined, its stdout read line by line."""

    def __init__(self, code: str, constants: dict, *args):
        preamble = "".join(f"{name} = {value!r}\n" for name, value in constants.items())
        self.process = subprocess.Popen(
            [sys.executable, "-c", preamble + textwrap.dedent(code), *map(str, args)],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.lines: list[str] = []

    def read_until(self, done) -> None:
        """Read lines until `done(lines)` holds; fail if the child ends first."""
        while not done(self.lines):
            line = self.process.stdout.readline()
            assert line, f"the child ended early: {self.process.wait()} {self.process.stderr.read()}"
            self.lines.append(line.strip())

    def kill(self) -> None:
        self.process.send_signal(signal.SIGKILL)
        remaining, errors = self.process.communicate(timeout=30)
        assert self.process.returncode == -signal.SIGKILL, errors
        self.lines += remaining.strip().splitlines()

    def finish(self) -> None:
        remaining, errors = self.process.communicate(timeout=60)
        assert self.process.returncode == 0, errors
        self.lines += remaining.strip().splitlines()

    def numbers(self, word: str) -> list[int]:
        """The N of each "word N" line; the kill can cut the last line short ("edi", "autosaved"): it says nothing."""
        lines = [line.split() for line in self.lines]
        return [int(parts[1]) for parts in lines if len(parts) == 2 and parts[0] == word and parts[1].isdigit()]


# ---------------------------------------------------------------- killed mid-save


@pytest.fixture(scope="module")
def versions(tmp_path_factory):
    """Two versions of a large scene, each saved in a folder of its own: (old path, new path)."""
    folder = tmp_path_factory.mktemp("versions")
    paths = folder / "old" / "scene.toml", folder / "new" / "scene.toml"
    for path, (description, seed) in zip(paths, [("old", 1), ("new", 2)]):
        save_scene(large_scene(description, seed), path)
    return paths


def saved_files(path) -> set[str]:
    """What lies beside a scene file: the TOML, its particle folder's files, anything else left behind."""
    return {str(file.relative_to(path.parent)) for file in path.parent.rglob("*") if file.is_file()}


def test_a_save_killed_at_any_rename_leaves_the_old_scene_whole(tmp_path, versions):
    old, new = (content(load_scene(path)) for path in versions)

    def saved_old(folder: str):
        target = tmp_path / folder / "scene.toml"
        save_scene(old, target)
        return target

    rehearsal_target = saved_old("rehearsal")
    rehearsal = Child(SAVING_CHILD, {"ANNOUNCE": True, "LOOP": False}, *versions, rehearsal_target)
    rehearsal.finish()
    renames = [line.split()[1] for line in rehearsal.lines if line.startswith("rename")]
    assert renames[-1] == "scene.toml" and len(renames) == 3  # the two changed clouds, then the TOML: the commit
    assert content(load_scene(rehearsal_target)) == new
    for killed_before, name in enumerate(renames):
        target = saved_old(f"killed before rename {killed_before}")
        child = Child(SAVING_CHILD, {"ANNOUNCE": True, "LOOP": False}, *versions, target)
        child.read_until(lambda lines, before=killed_before: sum(line.startswith("rename") for line in lines) > before)
        child.kill()
        assert content(load_scene(target)) == old, f"killed before renaming {name}"
        save_scene(old, target)  # the next save clears what the killed one left
        named = {cloud.particles_file for cloud in load_scene(target).clouds if cloud.particles_file}
        assert saved_files(target) == {target.name} | named


def test_saves_killed_after_random_delays_leave_one_scene_whole(tmp_path, versions):
    old, new = (content(load_scene(path)) for path in versions)
    target = tmp_path / "scene.toml"
    save_scene(old, target)
    delays = random.Random(9)
    for _ in range(3):
        child = Child(SAVING_CHILD, {"ANNOUNCE": False, "LOOP": True}, *versions, target)
        child.read_until(lambda lines: "ready" in lines)
        time.sleep(delays.uniform(0.05, 0.6))
        child.kill()
        assert content(load_scene(target)) in (old, new)


# ---------------------------------------------------------------- killed mid-edit


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "scene.toml"
    save_scene(large_scene("as saved", 3), path)
    return path


def check_recovery_after_the_crash(path, saved: Scene, child: Child) -> None:
    """The last save is intact, the copy holds every edit up to a minute before the crash, and the
    next start offers it, loads it as an undoable edit and saves it."""
    assert content(load_scene(path)) == saved
    recovered = load_scene(recovery_path(path))
    edits = int(recovered.description.split()[1])
    assert max(child.numbers("autosaved")) <= edits <= max(child.numbers("edit"))
    assert (max(child.numbers("edit")) - edits) * EDIT_SECONDS <= AUTOSAVE_SECONDS
    np.testing.assert_array_equal(
        recovered.clouds[0].particles[len(saved.clouds[0].particles) :, 0], np.arange(1.0, edits + 1)
    )

    editor = Editor.open(path)
    assert any(str(recovery_path(path)) in message for message in editor.messages)
    assert content(editor.scene) == saved
    assert editor.recover()
    assert content(editor.scene) == content(recovered) and editor.path == path and editor.dirty
    editor.undo()
    assert not editor.dirty
    editor.redo()
    assert editor.save()
    assert content(load_scene(path)) == content(recovered)
    assert not recovery_path(path).exists()
    assert not (path.parent / particles_folder(recovery_path(path))).exists()


def test_an_editor_killed_mid_autosave_loses_at_most_a_minute(scene_file):
    saved = content(load_scene(scene_file))
    child = Child(EDITING_CHILD, {"ANNOUNCE": True, "EDIT_SECONDS": EDIT_SECONDS}, scene_file)
    # the third autosave is about to commit (its TOML's rename) when the editor dies
    child.read_until(lambda lines: len(child.numbers("autosaved")) == 2 and lines[-1] == "rename scene.recovery.toml")
    child.kill()
    assert load_scene(recovery_path(scene_file)).description == f"edit {max(child.numbers('autosaved'))}"
    check_recovery_after_the_crash(scene_file, saved, child)


def test_an_editor_killed_at_a_random_moment_loses_at_most_a_minute(scene_file):
    saved = content(load_scene(scene_file))
    child = Child(EDITING_CHILD, {"ANNOUNCE": False, "EDIT_SECONDS": EDIT_SECONDS}, scene_file)
    child.read_until(lambda lines: len(child.numbers("autosaved")) >= 3)
    time.sleep(random.Random(4).uniform(0.0, 0.3))
    child.kill()
    check_recovery_after_the_crash(scene_file, saved, child)


def test_the_recovery_copy_never_touches_the_saved_scene_s_files(scene_file):
    before = {name: (scene_file.parent / name).read_bytes() for name in saved_files(scene_file)}
    editor = Editor.open(scene_file)
    cloud = editor.scene.clouds[0]
    editor.edit(
        dataclasses.replace(
            editor.scene, clouds=(dataclasses.replace(cloud, particles=cloud.particles[1:]), *editor.scene.clouds[1:])
        )
    )
    assert editor.autosave(now=time.monotonic() + AUTOSAVE_SECONDS)
    assert {name: (scene_file.parent / name).read_bytes() for name in before} == before
    assert len(load_scene(recovery_path(scene_file)).clouds[0].particles) == len(cloud.particles) - 1
    assert not editor.autosave(now=time.monotonic() + 3 * AUTOSAVE_SECONDS)  # nothing new to copy


def test_recover_without_a_recovery_file_says_so(scene_file):
    editor = Editor.open(scene_file)
    assert not any("recovery" in message for message in editor.messages)
    assert not editor.recover() and editor.messages[-1] == "there is no recovery file to load"
    assert not editor.dirty


def test_unsaved_edits_to_a_built_in_scene_are_kept_in_the_user_s_state_folder(tmp_path, monkeypatch):
    """The built-in scenes are the package's files (in site-packages where installed): an artist's edits to the
    default scene go to $XDG_STATE_HOME/cloudview/recovery, not beside it, and are offered again from there."""
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    packaged = set(DEFAULT_SCENE.parent.iterdir())
    editor = Editor.open(DEFAULT_SCENE)
    editor.set_time_of_day(9.0)
    assert editor.autosave(now=time.monotonic() + AUTOSAVE_SECONDS)
    kept = recovery_path(DEFAULT_SCENE)
    assert kept == tmp_path / "state" / "cloudview" / "recovery" / "valley.recovery.toml"
    assert load_scene(kept).lighting.time_of_day == 9.0 and len(load_scene(kept).clouds) == len(editor.scene.clouds)
    assert set(DEFAULT_SCENE.parent.iterdir()) == packaged
    assert any(str(kept) in message for message in Editor.open(DEFAULT_SCENE).messages)
