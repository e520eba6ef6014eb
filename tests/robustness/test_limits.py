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
from cloudcore.model.cloud_records import ArtistShading
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Camera, Cloud, Light, Lighting, Scene, Shading, Terrain
from cloudcore.scenes.editing import add_particle
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.limits import (
    DRAWN_TERRAIN_KINDS,
    MAX_FRAME_SIDE,
    MAX_LIGHTS,
    MAX_MAGNITUDE,
    MAX_NAME_LENGTH,
    frame_memory_problem,
    scene_limit_problems,
)

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
        "heightmap terrain only",
        '[terrain]\nkind = "heightfield"\n' + CLOUD,
    ),
    (
        "shading groups",
        ARTIST_CLOUD.format(size=1e-12),
        "clouds[0].shading_group_size",
        "too small",
        ARTIST_CLOUD.format(size=1.0),
    ),
    (
        "camera far out",
        "[camera]\nposition = [0, 800, 1e20]\nlook_at = [0, 800, 0]\n" + CLOUD,
        "camera.position",
        "within +-1e+12",
        f"[camera]\nposition = [0, 800, {MAX_MAGNITUDE}]\nlook_at = [0, 800, 0]\n" + CLOUD,
    ),
    (
        "particle far out",
        '[[clouds]]\nname = "c"\nparticles = [[0, 800, 0, 50], [1e200, 850, 0, 60]]\n',
        "clouds[0].particles",
        "within +-1e+12",
        f'[[clouds]]\nname = "c"\nparticles = [[0, 800, 0, 50], [{-MAX_MAGNITUDE}, 850, 0, {MAX_MAGNITUDE}]]\n',
    ),
    (
        "ambient past float32",
        "[lighting]\nambient = [1e39, 1e39, 1e39]\n" + CLOUD,
        "lighting.ambient",
        "within +-1e+12",
        f"[lighting]\nambient = [{MAX_MAGNITUDE}, 1, 1]\n" + CLOUD,
    ),
    (
        "albedo past one",
        "[shading]\nalbedo = 2.0\n" + CLOUD,
        "shading.albedo",
        "must be within",
        "[shading]\nalbedo = 1.0\n" + CLOUD,
    ),
    (
        "time of day past 24",
        "[lighting]\ntime_of_day = 30.0\n" + CLOUD,
        "lighting.time_of_day",
        "must be within",
        "[lighting]\ntime_of_day = 24.0\n" + CLOUD,
    ),
    (
        "negative optical depth",
        CLOUD + "optical_depth = -1.0\n",
        "clouds[0].optical_depth",
        "must be within",
        CLOUD + "optical_depth = 0.0\n",
    ),
    (
        "g past the phase's limit",
        "[shading]\ng = 1.0\n" + CLOUD,
        "shading.g",
        "must be within",
        "[shading]\ng = 0.999\n" + CLOUD,
    ),
    (
        "infinite radius",
        '[[clouds]]\nname = "c"\nparticles = [[0, 800, 0, inf]]\n',
        "clouds[0].particles",
        "finite",
        f'[[clouds]]\nname = "c"\nparticles = [[0, 800, 0, {MAX_MAGNITUDE}]]\n',
    ),
    (
        "long name",
        CLOUD.replace('"c"', f'"{"n" * (MAX_NAME_LENGTH + 1)}"'),
        "clouds[0].name",
        f"at most {MAX_NAME_LENGTH} characters",
        CLOUD.replace('"c"', f'"{"n" * MAX_NAME_LENGTH}"'),
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
    if name == "camera far out":
        return dataclasses.replace(base, camera=Camera((0.0, 800.0, 1e20), (0.0, 800.0, 0.0)))
    if name == "particle far out":
        return dataclasses.replace(base, clouds=(Cloud("c", np.array([[0, 800, 0, 50], [1e200, 850, 0, 60]])),))
    if name == "ambient past float32":
        return dataclasses.replace(base, lighting=Lighting(ambient=(1e39, 1e39, 1e39)))
    if name == "albedo past one":
        return dataclasses.replace(base, shading=Shading(albedo=2.0))
    if name == "time of day past 24":
        return dataclasses.replace(base, lighting=Lighting(time_of_day=30.0))
    if name == "negative optical depth":
        return dataclasses.replace(base, clouds=(dataclasses.replace(base.clouds[0], optical_depth=-1.0),))
    if name == "g past the phase's limit":
        return dataclasses.replace(base, shading=Shading(g=1.0))
    if name == "infinite radius":
        return dataclasses.replace(base, clouds=(Cloud("c", np.array([[0, 800, 0, np.inf]])),))
    if name == "long name":
        return dataclasses.replace(
            base, clouds=(dataclasses.replace(base.clouds[0], name="n" * (MAX_NAME_LENGTH + 1)),)
        )
    cloud = Cloud(
        "c", np.array([[0, 800, 0, 50], [1e5, 850, 0, 60]], float), artist=ArtistShading(), shading_group_size=1e-12
    )
    return dataclasses.replace(base, clouds=(cloud,))


#: what the renderer says past each limit it refuses or fails at, had the scene got that far
RENDERER_REFUSALS = {
    "lights": f"at most {MAX_LIGHTS} lights",
    "terrain kind": "heightmap terrain only",
    "shading groups": "too small for a cloud this large",
    "camera far out": "Singular matrix",  # the world pass inverts the view-projection
    "particle far out": "overflow",  # the shading's distances between particles
    # a typed number past a slider's range was applied, and the viewport raised these every frame
    "albedo past one": "albedo must be within",
    "time of day past 24": "time of day must be within",
    "negative optical depth": "optical_depth must be >= 0",
    "g past the phase's limit": "phase asymmetry g must be finite and within",
    "infinite radius": "radii must be finite",
}


@pytest.mark.parametrize("name", list(RENDERER_REFUSALS))
def test_the_renderer_fails_past_the_limit_so_the_check_guards_something(renderer, name):
    with pytest.raises(ValueError, match=RENDERER_REFUSALS[name]):
        renderer.render(past_limit(name))


@pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning")  # what it shows
def test_past_the_magnitude_limit_an_ambient_puts_inf_in_the_frame_so_the_check_guards_something(renderer):
    renderer.render(past_limit("ambient past float32"))
    assert not np.isfinite(renderer.context.read_linear_rgb()).all()


def test_past_the_name_limit_a_cloud_cannot_be_saved_so_the_check_guards_something(tmp_path):
    """A cloud of more than 64 particles goes to a file named after it; 240 characters are past the file system's
    255 bytes with the save's temporary name around them."""
    particles = np.column_stack([np.arange(100.0), np.full(100, 800.0), np.zeros(100), np.full(100, 50.0)])
    with pytest.raises(OSError, match="File name too long"):
        save_scene(Scene(clouds=(Cloud("n" * 240, particles),)), tmp_path / "s.toml")
    save_scene(Scene(clouds=(Cloud("n" * MAX_NAME_LENGTH, particles),)), tmp_path / "s.toml")
    assert len(load_scene(tmp_path / "s.toml").clouds[0].particles) == 100


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
        "c", np.array([[0, 800, 0, 50.0], [10, 800, 0, 50.0]]), artist=ArtistShading(), shading_group_size=1e-6
    )
    editor = Editor(Scene(clouds=(cloud,)), None)
    assert editor.change(lambda: add_particle(editor.scene, 0, (1e11, 800.0, 0.0), 50.0)) is False
    assert editor.scene.clouds[0] is cloud
    assert "clouds[0].shading_group_size" in editor.messages[-1]
    assert editor.change(lambda: add_particle(editor.scene, 0, (1e17, 800.0, 0.0), 50.0)) is False
    assert "clouds[0].particles: numbers must be within" in editor.messages[-1]
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
    from cloudcore.gl import splat_residency, splat_shading

    # the particles' records hold MAX_LIGHTS incident lights; the shading shader sums as many
    assert splat_residency.MAX_LIGHTS is MAX_LIGHTS and splat_shading.MAX_LIGHTS is MAX_LIGHTS


@pytest.mark.parametrize("side, status", [(MAX_FRAME_SIDE + 1, 2), (0, 2)])
def test_a_frame_side_past_the_limit_is_refused_at_the_command_line(tmp_path, side, status):
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "render", "--out", str(tmp_path / "x.png"), "--width", str(side)],
        capture_output=True,
        text=True,
    )
    assert result.returncode == status
    assert len(result.stderr.strip().splitlines()) == 1 and "--width" in result.stderr


def test_a_frame_past_the_memory_available_is_refused_naming_what_it_needs():
    problem = frame_memory_problem(16384, 16384, available_bytes=8 * 10**9)
    assert problem is not None and "16384x16384" in problem and "8.0 GB are available" in problem
    assert frame_memory_problem(640, 480, available_bytes=8 * 10**9) is None


@pytest.mark.parametrize(
    "arguments, words, output",
    [
        (["render", "--out", "{tmp}/x"], "not an image file name", "x"),
        (["render", "--out", "{tmp}/x.png", "--camera-path", "orbit", "--path-time", "nan"], "--path-time", "x.png"),
        (["bench", "--still", "--frames", "1", "--json", "{tmp}/folder"], "is a folder", "folder/x"),
        (["record", "--camera-path", "orbit", "--out", "{tmp}/video"], "not a video file name", "video"),
    ],
)
def test_bad_outputs_and_times_are_refused_in_one_line_before_any_frame(
    tmp_path, small_scene, arguments, words, output
):
    scene = tmp_path / "scene.toml"
    save_scene(small_scene, scene)
    (tmp_path / "folder").mkdir()
    command = [arguments[0], str(scene), *(a.replace("{tmp}", str(tmp_path)) for a in arguments[1:])]
    result = subprocess.run([sys.executable, "-m", "cloudcore.cli", *command], capture_output=True, text=True)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1 and words in result.stderr, result.stderr
    assert not (tmp_path / output).exists()
