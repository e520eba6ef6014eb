"""GLSL programs built from the .glsl files in `shaders/`, with constants injected as #defines.

Constants shared with the numpy side (such as the splat sharpness) are
injected rather than written twice, so the two cannot drift apart; declarations
shared by shaders live in a file of their own, which a line `#include "file.glsl"`
stands for.  Compile and link errors raise with the driver's log and the file name.
"""

from __future__ import annotations

import functools
import re
from importlib.resources import files

import numpy as np
from OpenGL import GL

#: the .glsl files, package data (found in an installed wheel as in a checkout)
SHADER_DIR = files("cloudcore.gl").joinpath("shaders")


class ShaderError(RuntimeError):
    """A shader failed to compile or a program failed to link."""


def build_program(name: str, defines: dict[str, int | float] | None = None, vertex: str | None = None) -> int:
    """Compile shaders/VERTEX.vert.glsl (VERTEX defaults to NAME) and NAME.frag.glsl, link; returns the id."""
    stages = [(GL.GL_VERTEX_SHADER, f"{vertex or name}.vert.glsl"), (GL.GL_FRAGMENT_SHADER, f"{name}.frag.glsl")]
    return _link(name, [_compile(kind, file, defines or {}) for kind, file in stages])


class ProgramCache:
    """Programs built once for a GL context and kept while it lives: a pass made again for a new light (each look of
    a dragged time-of-day slider makes the world pass again) takes its programs from here instead of compiling them
    again, which cost llvmpipe about 15 ms a program (docs/performance.md, "The world pass within its budget")."""

    def __init__(self):
        self._programs: dict[tuple, int] = {}

    def program(self, name: str, defines: dict[str, int | float] | None = None, vertex: str | None = None) -> int:
        """`build_program(name, defines, vertex)`'s program, built on the first call; the context must be current."""
        key = name, tuple(sorted((defines or {}).items())), vertex
        if key not in self._programs:
            self._programs[key] = build_program(name, defines, vertex)
        return self._programs[key]

    def close(self) -> None:
        """Delete the programs built (the context must be current)."""
        for program in self._programs.values():
            GL.glDeleteProgram(program)
        self._programs.clear()


def build_compute_program(name: str, defines: dict[str, int | float] | None = None) -> int:
    """Compile shaders/NAME.comp.glsl and link it alone; returns the program id."""
    return _link(name, [_compile(GL.GL_COMPUTE_SHADER, f"{name}.comp.glsl", defines or {})])


def _link(name: str, shaders: list[int]) -> int:
    program = GL.glCreateProgram()
    for shader in shaders:
        GL.glAttachShader(program, shader)
    GL.glLinkProgram(program)
    for shader in shaders:
        GL.glDetachShader(program, shader)
        GL.glDeleteShader(shader)
    if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
        log = _text(GL.glGetProgramInfoLog(program))
        GL.glDeleteProgram(program)
        raise ShaderError(f"program {name!r} failed to link:\n{log}")
    return program


#: a line that stands for a file of `shaders/`: declarations shared by the shaders that include it
_INCLUDE = re.compile(r'^#include "([\w.]+)"[^\n]*$', re.MULTILINE)


def _compile(kind: int, file: str, defines: dict[str, int | float]) -> int:
    source = SHADER_DIR.joinpath(file).read_text(encoding="utf-8")
    source = _INCLUDE.sub(lambda include: _included(source, include), source)
    version, _, body = source.partition("\n")
    if not version.startswith("#version"):
        raise ShaderError(f"{file}: the first line must be the #version directive")
    # integers stay integers (array sizes); everything else is written as a float literal
    lines = [version] + [
        f"#define {key} {value if isinstance(value, int) else float(value)!r}" for key, value in defines.items()
    ]
    # keep the driver's line numbers pointing into the file
    lines.append("#line 2")
    shader = GL.glCreateShader(kind)
    GL.glShaderSource(shader, "\n".join(lines) + "\n" + body)
    GL.glCompileShader(shader)
    if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
        log = _text(GL.glGetShaderInfoLog(shader))
        GL.glDeleteShader(shader)
        raise ShaderError(f"{file} failed to compile:\n{log}")
    return shader


def _included(source: str, include: re.Match) -> str:
    """The text of the file `include` names, then a #line that numbers the includer's next line as its own."""
    next_line = source.count("\n", 0, include.start()) + 2
    return f"{SHADER_DIR.joinpath(include.group(1)).read_text(encoding='utf-8')}#line {next_line}"


def _text(log) -> str:
    return log.decode(errors="replace") if isinstance(log, bytes) else str(log)


def uniform_locations(program: int, names) -> dict[str, int]:
    """The locations of a program's uniforms `names`, looked up once for a pass that sets them every draw."""
    return {name: GL.glGetUniformLocation(program, name) for name in names}


def set_matrix(program: int, name: str, matrix) -> None:
    """Upload a 4x4 numpy matrix (row-major, as numpy stores it) to a mat4 uniform."""
    set_matrix_at(GL.glGetUniformLocation(program, name), matrix)


def set_matrix_at(location: int, matrix) -> None:
    """`set_matrix` for a uniform whose location is known (`uniform_locations`)."""
    GL.glUniformMatrix4fv(location, 1, GL.GL_TRUE, np.ascontiguousarray(matrix, dtype=np.float32))


def set_vec3(program: int, name: str, value) -> None:
    set_vec3_at(GL.glGetUniformLocation(program, name), value)


def set_vec3_at(location: int, value) -> None:
    GL.glUniform3f(location, *(float(v) for v in value))


@functools.cache
def max_dispatch_groups() -> int:
    """The most work groups one dispatch may ask for along x (GL_MAX_COMPUTE_WORK_GROUP_COUNT), read once: GL
    guarantees 65,535, llvmpipe's, which 4.2 million particles in groups of 64 would pass."""
    return int(np.asarray(GL.glGetIntegeri_v(GL.GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0)).ravel()[0])


def gl_renderer() -> str:
    """GL_RENDERER of the current context: which GL this is (llvmpipe, a GPU)."""
    renderer = GL.glGetString(GL.GL_RENDERER)
    return renderer.decode() if isinstance(renderer, bytes) else str(renderer)


def dispatch(groups: int) -> None:
    """Dispatch the current compute program over `groups` work groups along x, at most as many as the GL
    allows: the shaders dispatched this way loop, each invocation (or group) taking every so many items."""
    if groups > 0:
        GL.glDispatchCompute(min(int(groups), max_dispatch_groups()), 1, 1)
