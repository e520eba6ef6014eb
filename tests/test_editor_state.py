"""The editor's state stays one the panels can draw and the artist's work is never dropped, whatever is typed or
clicked in whatever order (a helper's fuzzing of the editor found each of these raising every frame or losing work)."""

import dataclasses
import math
import os

import numpy as np
import pytest

from app.editor import Editor, recovery_path
from app.tools import ViewportTools
from cloudcore.editing import add_cloud
from cloudcore.scene import Cloud, Scene
from cloudcore.scenefile import load_scene, save_scene


def one_cloud_scene() -> Scene:
    return Scene(clouds=(Cloud("c", np.array([[0, 800, 0, 50.0]])),))


def test_undoing_the_cloud_just_added_and_selected_leaves_a_cloud_selected_that_the_scene_has():
    editor = Editor(one_cloud_scene(), None)
    assert editor.edit(add_cloud(editor.scene))
    editor.selected_cloud = 1
    editor.undo()
    assert editor.selected_cloud == 0
    editor.redo()
    editor.selected_cloud = 1
    editor.edit(dataclasses.replace(editor.scene, clouds=()))  # every cloud deleted
    assert editor.selected_cloud is None
    editor.undo()
    assert editor.selected_cloud == 0  # a cloud is back: the panels select one, as on opening


def test_a_time_of_day_or_albedo_past_its_range_is_refused_and_the_scene_kept():
    editor = Editor(one_cloud_scene(), None)
    before = editor.scene
    for hours in (30.0, -1.0, math.inf, math.nan):
        editor.set_time_of_day(hours)
        assert editor.scene is before and editor.messages[-1].startswith("not applied: lighting.time_of_day: ")


def test_opening_another_scene_keeps_the_unsaved_edits_in_the_recovery_copy(tmp_path):
    first, second = tmp_path / "first.toml", tmp_path / "second.toml"
    save_scene(one_cloud_scene(), first)
    save_scene(Scene(), second)
    editor = Editor.open(first)
    assert editor.edit(add_cloud(editor.scene, "unsaved"))
    assert editor.open_file(second)
    assert editor.path == second and not editor.dirty
    assert [c.name for c in load_scene(recovery_path(first)).clouds] == ["c", "unsaved"]
    assert any(str(recovery_path(first)) in message for message in editor.messages)
    assert editor.open_file(first)  # reopened, the edits are offered and come back
    assert "Recover unsaved edits" in editor.messages[-1]
    assert editor.recover() and [c.name for c in editor.scene.clouds] == ["c", "unsaved"]


def test_a_scene_with_unsaved_edits_and_no_file_stays_open(tmp_path):
    other = tmp_path / "other.toml"
    save_scene(Scene(), other)
    editor = Editor(one_cloud_scene(), None)
    assert editor.edit(add_cloud(editor.scene))
    edited = editor.scene
    assert not editor.open_file(other)
    assert editor.scene is edited and "Save as first" in editor.messages[-1]


def test_an_unusable_brush_rate_is_a_message_and_leaves_no_gesture_open():
    editor = Editor(one_cloud_scene(), None)
    editor.tool, editor.brush_rate = "brush", 0.0
    tools = ViewportTools(editor)
    tools.press((np.array([0.0, 2000.0, 0.0]), np.array([0.0, -1.0, 0.0])), screen_plane=False)
    assert not editor.history.in_gesture and not tools.busy
    assert "brush rate must be finite and > 0" in editor.messages[-1]


def test_a_path_time_that_is_not_a_number_is_a_message(small_scene):
    editor = Editor(small_scene, None)
    camera = editor.camera
    editor.show_path_time(math.nan)
    assert editor.camera is camera and "must be finite" in editor.messages[-1]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_opening_a_pipe_is_refused_instead_of_waiting_for_ever(tmp_path):
    pipe = tmp_path / "scene.toml"
    os.mkfifo(pipe)
    editor = Editor(one_cloud_scene(), None)
    assert not editor.open_file(pipe)
    assert "not a regular file" in editor.messages[-1]
