"""Shaders built from `shaders/` (`cloudcore.gl.programs`): a line `#include "file.glsl"` stands for the
file's declarations, and the driver's line numbers still point into the including file."""

import pytest


@pytest.fixture
def shaders(tmp_path, monkeypatch):
    from cloudcore.gl import programs

    monkeypatch.setattr(programs, "SHADER_DIR", tmp_path)
    (tmp_path / "shared.glsl").write_text(
        "// shared\nconst uint SHARED = 7u;\nlayout(std430, binding = 0) buffer Out { uint values[]; };\n"
    )
    return tmp_path


def test_an_included_file_declares_what_the_shader_uses(renderer, shaders):
    from OpenGL import GL

    from cloudcore.gl.programs import build_compute_program

    (shaders / "uses.comp.glsl").write_text(
        '#version 430 core\n#include "shared.glsl"  // SHARED and the buffer\nlayout(local_size_x = 1) in;\n'
        "void main() { values[0] = SHARED; }\n"
    )
    renderer.context.make_current()
    program = build_compute_program("uses")
    assert GL.glIsProgram(program)
    GL.glDeleteProgram(program)


def test_errors_after_an_include_name_the_including_files_line(renderer, shaders):
    from cloudcore.gl.programs import ShaderError, build_compute_program

    (shaders / "broken.comp.glsl").write_text(
        '#version 430 core\n#include "shared.glsl"\nlayout(local_size_x = 1) in;\n'
        "void main() { values[0] = missing; }\n"
    )
    renderer.context.make_current()
    with pytest.raises(ShaderError, match=r"broken\.comp\.glsl failed to compile:\n0:4\(") as error:
        build_compute_program("broken")
    assert "missing" in str(error.value)


@pytest.mark.gl
def test_a_new_light_makes_the_world_pass_again_without_compiling_its_programs(renderer, monkeypatch):
    """Each look of a dragged time-of-day slider makes the world pass again (a new light): its programs (the
    terrain's, the sky's, the light shafts') come from the frame's `ProgramCache`, none compiled again, and the
    picture follows the light."""
    from cloudcore.gl import programs
    from cloudcore.resources import DEFAULT_SCENE
    from cloudcore.scenes.files import load_scene

    scene = load_scene(DEFAULT_SCENE)
    first = renderer.render(scene, time_of_day=15.0)[0]
    built = []
    original = programs._link  # what every program built goes through, whoever calls build_program
    monkeypatch.setattr(programs, "_link", lambda name, shaders: built.append(name) or original(name, shaders))
    second = renderer.render(scene, time_of_day=15.25)[0]
    world_programs = {"terrain", "terrain_depth", "sky", "sky_read", "light_shafts", "light_shafts_blur"}
    assert not world_programs & set(built), built
    assert renderer.light_shafts is not None  # the shafts were drawn: their programs were asked for
    assert abs(second.astype(int) - first.astype(int)).max() > 4
