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
