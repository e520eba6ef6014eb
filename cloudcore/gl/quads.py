"""Textured quads: impostors, ring panels and screen impostors, blended premultiplied."""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.blending import cloud_blending
from cloudcore.gl.programs import build_program, set_matrix_at, uniform_locations

#: clip-space corners of the whole screen, for screen impostors
SCREEN_CORNERS = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0]], dtype=np.float64)


class QuadPass:
    def __init__(self):
        self._program = build_program("quad")
        self._crossfade_program = build_program("quad", {"CROSSFADE": 1})
        self._counting_program = build_program("quad", {"COUNT_FRAGMENTS": 1})
        #: per program, the locations of the uniforms every draw sets
        self._uniforms = {}
        for program in (self._program, self._crossfade_program, self._counting_program):
            GL.glUseProgram(program)
            GL.glUniform1i(GL.glGetUniformLocation(program, "impostor"), 0)
            GL.glUniform1i(GL.glGetUniformLocation(program, "layer"), 1)
            self._uniforms[program] = uniform_locations(
                program, ("corners", "uv_rect", "view_projection", "impostor_weight", "layer_weight")
            )
        #: core profile draws nothing without a vertex array, even one with no attributes; shared
        #: with the other attribute-less passes
        self.vertex_array = GL.glGenVertexArrays(1)

    def draw(
        self,
        corners: np.ndarray,
        view_projection: np.ndarray,
        texture: int,
        impostor_weight: float,
        *,
        layer_texture: int | None = None,
        layer_weight: float = 0.0,
        depth_test: bool = True,
        counting: bool = False,
        uv_rect=(0.0, 0.0, 1.0, 1.0),
    ) -> None:
        """Blend `texture` (premultiplied) over the bound target on the quad `corners` (4, 3), which show
        the part `uv_rect` (u0, v0, u1, v1) of the texture."""
        program = (
            self._counting_program
            if counting
            else self._crossfade_program
            if layer_texture is not None
            else self._program
        )
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        GL.glUniform3fv(uniforms["corners"], 4, np.ascontiguousarray(corners, dtype=np.float32))
        set_matrix_at(uniforms["view_projection"], view_projection)
        GL.glUniform4f(uniforms["uv_rect"], *map(float, uv_rect))
        GL.glUniform1f(uniforms["impostor_weight"], float(impostor_weight))
        GL.glUniform1f(uniforms["layer_weight"], float(layer_weight))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        if layer_texture is not None:
            GL.glActiveTexture(GL.GL_TEXTURE1)
            GL.glBindTexture(GL.GL_TEXTURE_2D, layer_texture)
            GL.glActiveTexture(GL.GL_TEXTURE0)
        with cloud_blending(depth_test, counting):
            GL.glBindVertexArray(self.vertex_array)
            GL.glDrawArrays(GL.GL_TRIANGLE_STRIP, 0, 4)
            GL.glBindVertexArray(0)

    def draw_run(self, quads, view_projection: np.ndarray, *, counting: bool = False) -> None:
        """`draw` for a run of depth-tested world-space quads, each (corners, texture, weight, uv_rect): the
        program, the matrix and the blending set once for all."""
        program = self._counting_program if counting else self._program
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_projection"], view_projection)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        corners_at, uv_at, weight_at = uniforms["corners"], uniforms["uv_rect"], uniforms["impostor_weight"]
        with cloud_blending(True, counting):
            GL.glBindVertexArray(self.vertex_array)
            for corners, texture, weight, (u0, v0, u1, v1) in quads:
                GL.glUniform3fv(corners_at, 4, corners)
                GL.glUniform4f(uv_at, u0, v0, u1, v1)
                GL.glUniform1f(weight_at, weight)
                GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
                GL.glDrawArrays(GL.GL_TRIANGLE_STRIP, 0, 4)
            GL.glBindVertexArray(0)

    def close(self) -> None:
        for program in self._uniforms:
            GL.glDeleteProgram(program)
        GL.glDeleteVertexArrays(1, [self.vertex_array])
