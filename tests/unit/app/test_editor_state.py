"""The editor's state stays one the panels can draw and the artist's work is never dropped, whatever is typed or
clicked in whatever order (a helper's fuzzing of the editor found each of these raising every frame or losing work)."""

import dataclasses
import math
import os

import numpy as np
import pytest

from app.editor import Editor, recovery_path
from app.tools import ViewportTools
from cloudcore.model.scene import Camera, Cloud, Scene
from cloudcore.scenes.editing import add_cloud
from cloudcore.scenes.files import load_scene, save_scene


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


def test_camera_keys_are_added_moved_and_deleted_as_undoable_edits_within_the_paths_rules():
    """With no path, a key at the view makes one from the scene's camera; a move past a neighbour, a NaN time
    and a delete leaving one key are messages, the scene kept; undo walks back every edit."""
    editor = Editor(one_cloud_scene(), None)
    editor.camera = Camera((100.0, 500.0, 900.0), (0.0, 800.0, 0.0))
    assert editor.add_camera_key(4.0)
    path = editor.scene.camera_path(editor.camera_path_name)
    assert path.keys.tolist() == [[0.0, 0.0, 500.0, 3000.0, 0.0, 700.0, 0.0], [4.0, 100, 500, 900, 0, 800, 0]]
    editor.camera = Camera((0.0, 600.0, 500.0), (0.0, 800.0, 0.0))
    assert editor.add_camera_key(2.0)  # between the two: kept in time order
    assert editor.scene.camera_path("path").keys[:, 0].tolist() == [0.0, 2.0, 4.0]
    three = editor.scene
    for refused in (lambda: editor.move_camera_key(1, 5.0), lambda: editor.move_camera_key(1, math.nan)):
        assert not refused() and editor.scene is three
    assert "key times must increase strictly" in editor.messages[-2] and "finite" in editor.messages[-1]
    assert editor.move_camera_key(1, 3.0) and editor.delete_camera_key(0)
    assert editor.scene.camera_path("path").keys[:, 0].tolist() == [3.0, 4.0]
    assert not editor.delete_camera_key(0)
    assert "a camera path needs at least 2 keys" in editor.messages[-1]
    for _ in range(4):
        editor.undo()
    assert editor.scene.camera_paths == ()


def test_a_camera_path_file_the_editor_cannot_import_is_a_message_and_the_scene_kept(tmp_path):
    editor = Editor(one_cloud_scene(), None)
    (tmp_path / "bad.csv").write_text("t,px,py,pz,lx,ly,lz\n0,0,0,0,1,0,0\n0,1,0,0,2,0,0\n")
    before = editor.scene
    assert not editor.import_camera_path(tmp_path / "bad.csv")
    assert (
        editor.scene is before and f"could not import: {tmp_path / 'bad.csv'}: keys: key times" in editor.messages[-1]
    )
    assert not editor.export_camera_path(tmp_path / "out.csv")
    assert editor.messages[-1] == "the scene has no camera path to export" and not (tmp_path / "out.csv").exists()
