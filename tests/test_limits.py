"""The audit of issue 18: every limit the renderer has is refused when a scene is loaded and when the editor edits it.

Each limit has the same four checks: the renderer really does fail past it (so
the check guards something), the loader refuses a file past it in one line
naming file and field, `cloudview render` exits 2 with that line, and the
editor refuses the edit with a message and keeps the scene.  The frame size,
an argument rather than a scene field, is checked at the command line.
"""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from app.editor import Editor
from cloudcore.cloud_records import ArtistShading
from cloudcore.editing import add_particle
from cloudcore.errors import SceneError
from cloudcore.limits import DRAWN_TERRAIN_KINDS, MAX_FRAME_SIDE, MAX_LIGHTS, scene_limit_problems
from cloudcore.scene import Cloud, Light, Lighting, Scene, Terrain
from cloudcore.scenefile import load_scene

pytestmark = pytest.mark.gl

CLOUD = '[[clouds]]\nname = "c"\nparticles = [[0, 800, 0, 50], [100, 850, 0, 60]]\n'
ARTIST_CLOUD = (
    '[[clouds]]\nname = "c"\nparticles = [[0, 800, 0, 50], [1e5, 850, 0, 60]]\n'
    "shading_group_size = {size}\nartist = {{}}\n"
)


def lights_toml(count: int, dark: int = 0) -> str:
    return (
        "".join(
            f"[[lighting.lights]]\ndirection = [0, 1, 0]\nintensity = {0 if i < dark else 1}\n" for i in range(count)
        )
        + CLOUD
    )


#: (name, file past the limit, field, words of the problem, file just within it)
LIMITS = [
    (
        "lights",
        lights_toml(MAX_LIGHTS + 1),
        "lighting.lights",
        f"at most {MAX_LIGHTS} lights",
        lights_toml(MAX_LIGHTS + 1, dark=1),
    ),
    (
        "terrain kind",
        '[terrain]\nkind = "mesh"\nmesh = "ground.obj"\n' + CLOUD,
        "terrain.kind",
        "heightfield terrain only",
        '[terrain]\nkind = "heightfield"\n' + CLOUD,
    ),
    (
        "shading groups",
        ARTIST_CLOUD.format(size=1e-12),
        "clouds[0].shading_group_size",
        "too small",
        ARTIST_CLOUD.format(size=1.0),
    ),
]


def past_limit(name: str) -> Scene:
    """The scene of LIMITS[name] past its limit, made in code (the loader would refuse the file)."""
    base = Scene(clouds=(Cloud("c", np.array([[0, 800, 0, 50], [100, 850, 0, 60]], float)),))
    if name == "lights":
        lights = tuple(Light((0.0, 1.0, 0.0)) for _ in range(MAX_LIGHTS + 1))
        return dataclasses.replace(base, lighting=Lighting(time_of_day=None, lights=lights))
    if name == "terrain kind":
        return dataclasses.replace(base, terrain=Terrain(kind="mesh", mesh="ground.obj"))
    cloud = Cloud(
        "c", np.array([[0, 800, 0, 50], [1e5, 850, 0, 60]], float), artist=ArtistShading(), shading_group_size=1e-12
    )
    return dataclasses.replace(base, clouds=(cloud,))


#: what the GL side says past each limit, had the scene got that far
RENDERER_REFUSALS = {
    "lights": f"at most {MAX_LIGHTS} lights",
    "terrain kind": "heightfield terrain only",
    "shading groups": "too small for a cloud this large",
}


@pytest.mark.parametrize("name", [limit[0] for limit in LIMITS])
def test_the_renderer_fails_past_the_limit_so_the_check_guards_something(renderer, name):
    with pytest.raises(ValueError, match=RENDERER_REFUSALS[name]):
        renderer.render(past_limit(name))


@pytest.mark.parametrize("name, text, field, problem, within", LIMITS)
def test_the_loader_refuses_a_scene_past_the_limit_naming_file_and_field(tmp_path, name, text, field, problem, within):
    (tmp_path / "ok.toml").write_text(within)
    load_scene(tmp_path / "ok.toml")  # just within: loads
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert (caught.value.source, caught.value.field) == (str(path), field)
    assert problem in caught.value.problem


@pytest.mark.parametrize("name, text, field, problem, within", LIMITS)
def test_cloudview_render_refuses_it_in_one_line_with_status_2(tmp_path, name, text, field, problem, within):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "render", str(path), "--out", str(tmp_path / "x.png")],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cloudview: error: {path}: {field}: ") and problem in lines[0]
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("name, text, field, problem, within", LIMITS)
def test_the_editor_refuses_the_edit_with_a_message_and_keeps_the_scene(name, text, field, problem, within):
    editor = Editor(Scene(clouds=(Cloud("c", np.array([[0, 800, 0, 50.0]])),)), None)
    before = editor.scene
    assert editor.edit(past_limit(name)) is False
    assert editor.scene is before and not editor.dirty
    assert editor.messages[-1].startswith(f"not applied: {field}: ") and problem in editor.messages[-1]
    editor.undo()  # nothing was recorded to undo
    assert editor.scene is before


def test_placing_a_particle_far_outside_an_artist_cloud_is_refused_and_the_cloud_kept():
    cloud = Cloud(
        "c", np.array([[0, 800, 0, 50.0], [10, 800, 0, 50.0]]), artist=ArtistShading(), shading_group_size=1.0
    )
    editor = Editor(Scene(clouds=(cloud,)), None)
    assert editor.change(lambda: add_particle(editor.scene, 0, (1e17, 800.0, 0.0), 50.0)) is False
    assert editor.scene.clouds[0] is cloud
    assert "clouds[0].shading_group_size" in editor.messages[-1]
    assert editor.change(lambda: add_particle(editor.scene, 0, (1e3, 800.0, 0.0), 50.0)) is True
    assert len(editor.scene.clouds[0].particles) == 3


def test_an_edit_the_editing_functions_refuse_is_a_message_not_a_traceback():
    editor = Editor(Scene(clouds=(Cloud("c", np.array([[0, 800, 0, 50.0]])),)), None)
    before = editor.scene
    assert editor.change(lambda: add_particle(editor.scene, 0, (0.0, 900.0, 0.0), 0.0)) is False
    assert editor.scene is before and "radius > 0" in editor.messages[-1]


def test_a_scene_within_every_limit_has_no_problems(small_scene):
    assert scene_limit_problems(small_scene) == []
    assert small_scene.terrain.kind in DRAWN_TERRAIN_KINDS


def test_the_shader_s_light_array_is_sized_by_the_same_constant():
    from cloudcore.gl import splats

    assert splats.MAX_LIGHTS is MAX_LIGHTS


@pytest.mark.parametrize("side, status", [(MAX_FRAME_SIDE + 1, 2), (0, 2)])
def test_a_frame_side_past_the_limit_is_refused_at_the_command_line(tmp_path, side, status):
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "render", "--out", str(tmp_path / "x.png"), "--width", str(side)],
        capture_output=True,
        text=True,
    )
    assert result.returncode == status
    assert len(result.stderr.strip().splitlines()) == 1 and "--width" in result.stderr
