"""Textured quads: impostors, ring panels and screen impostors, blended premultiplied; world-space ones seen
through the air from the eye's place now, when the frame has an air (`AirVolume`)."""

from __future__ import annotations

import ctypes

import numpy as np
from OpenGL import GL

from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.blending import cloud_blending
from cloudcore.gl.impostor_atlas import INSTANCE_FLOATS
from cloudcore.gl.light_shafts import FrameShafts
from cloudcore.gl.programs import build_program, set_matrix_at, set_vec3, uniform_locations
from cloudcore.light.air_between import air_cells

#: clip-space corners of the whole screen, for screen impostors
SCREEN_CORNERS = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0]], dtype=np.float64)

#: (location, floats) of the instance attributes of quad.vert.glsl's ATLAS variant, in `INSTANCE_FLOATS` order
_INSTANCE_ATTRIBUTES = ((0, 3), (1, 3), (2, 3), (3, 3), (4, 4), (5, 4), (6, 2))


class QuadPass:
    def __init__(self):
        #: (seen through the air, counting) -> the program drawing quads from uniforms
        self._programs = {
            (False, False): build_program("quad"),
            (True, False): build_program("quad", {"AIR": 1}),
            (False, True): build_program("quad", {"COUNT_FRAGMENTS": 1}),
        }
        #: Wang's ring's panels, each fragment at its clouds' depth (`draw_panels`)
        self._panel_program = build_program("quad", {"PANEL_DEPTH": 1})
        #: (crossfade, counting, seen through the air, less the light shafts' share of it) -> the program drawing
        #: instances from the atlas
        self._atlas_programs = {
            (False, False, False, False): build_program("quad", {"ATLAS": 1}),
            (True, False, False, False): build_program("quad", {"ATLAS": 1, "CROSSFADE": 1}),
            (False, True, False, False): build_program("quad", {"ATLAS": 1, "COUNT_FRAGMENTS": 1}),
        } | {
            (crossfade, False, True, shafts): build_program(
                "quad",
                {"ATLAS": 1, "AIR": 1}
                | ({"CROSSFADE": 1} if crossfade else {})
                | ({"LIGHT_SHAFTS": 1} if shafts else {}),
            )
            for crossfade in (False, True)
            for shafts in (False, True)
        }
        #: per program, the locations of the uniforms every draw sets
        self._uniforms = {}
        for program in (*self._programs.values(), *self._atlas_programs.values(), self._panel_program):
            GL.glUseProgram(program)
            GL.glUniform1i(GL.glGetUniformLocation(program, "impostor"), 0)
            GL.glUniform1i(GL.glGetUniformLocation(program, "layer"), 1)
            GL.glUniform1i(GL.glGetUniformLocation(program, "panel_depth"), 2)
            self._uniforms[program] = uniform_locations(
                program,
                ("corners", "uv_rect", "view_projection", "impostor_weight", "layer_weight", "air_cells")
                + (("panel_eye", "panel_distance", "segment_near_far") if program == self._panel_program else ()),
            )
        #: core profile draws nothing without a vertex array, even one with no attributes; shared
        #: with the other attribute-less passes
        self.vertex_array = GL.glGenVertexArrays(1)
        self._instance_array, self._instance_buffer = GL.glGenVertexArrays(1), GL.glGenBuffers(1)
        GL.glBindVertexArray(self._instance_array)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._instance_buffer)
        offset = 0
        for location, floats in _INSTANCE_ATTRIBUTES:
            GL.glEnableVertexAttribArray(location)
            GL.glVertexAttribPointer(
                location, floats, GL.GL_FLOAT, GL.GL_FALSE, 4 * INSTANCE_FLOATS, ctypes.c_void_p(4 * offset)
            )
            GL.glVertexAttribDivisor(location, 1)
            offset += floats
        GL.glBindVertexArray(0)

    def draw(
        self,
        corners: np.ndarray,
        view_projection: np.ndarray,
        texture: int,
        impostor_weight: float,
        *,
        depth_test: bool = True,
        counting: bool = False,
        uv_rect=(0.0, 0.0, 1.0, 1.0),
    ) -> None:
        """Blend `texture` (premultiplied) over the bound target on the quad `corners` (4, 3), which show
        the part `uv_rect` (u0, v0, u1, v1) of the texture."""
        self.draw_run([(corners, texture, impostor_weight, uv_rect)], view_projection, depth_test, counting=counting)

    def draw_run(
        self,
        quads,
        view_projection: np.ndarray,
        depth_test: bool = True,
        *,
        counting: bool = False,
        air: tuple[AirVolume, np.ndarray] | None = None,
    ) -> None:
        """`draw` for a run of quads, each (corners, texture, weight, uv_rect): the program, the matrix and the
        blending set once for all; with `air` (the volume, the eye), world-space quads seen through it."""
        program = self._programs[air is not None and not counting, counting]
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_projection"], view_projection)
        self._see_through(program, air, counting)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        corners_at, uv_at, weight_at = uniforms["corners"], uniforms["uv_rect"], uniforms["impostor_weight"]
        cells = air_cells(np.array([quad[0] for quad in quads]), air[1]) if air is not None and not counting else None
        with cloud_blending(depth_test, counting):
            GL.glBindVertexArray(self.vertex_array)
            for i, (corners, texture, weight, (u0, v0, u1, v1)) in enumerate(quads):
                GL.glUniform3fv(corners_at, 4, np.ascontiguousarray(corners, dtype=np.float32))
                GL.glUniform4f(uv_at, u0, v0, u1, v1)
                GL.glUniform1f(weight_at, weight)
                GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
                if cells is None:
                    GL.glDrawArrays(GL.GL_TRIANGLE_STRIP, 0, 4)
                else:
                    _draw_cells(uniforms["air_cells"], int(cells[i]), 1)
            GL.glBindVertexArray(0)

    def draw_panels(self, panels, view_projection: np.ndarray, segment_projection: np.ndarray) -> None:
        """Ring panels, each (corners, texture, its nearest depth texture, weight, uv_rect, the ring's eye, the
        panel's distance from it along its segment's middle), drawn as `draw_run` draws quads but each fragment
        tested at the depth of the nearest particle its segment holds there (seen through `segment_projection`,
        `cloudcore.lod.ring.segment_camera`'s): terrain nearer than a panel's clouds hides them, as in full 3D."""
        program = self._panel_program
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_projection"], view_projection)
        # the planes of an OpenGL perspective projection, from its third row
        (_, _, z_scale, z_offset) = segment_projection[2]
        GL.glUniform2f(uniforms["segment_near_far"], z_offset / (z_scale - 1.0), z_offset / (z_scale + 1.0))
        with cloud_blending(depth_test=True, counting=False):
            GL.glBindVertexArray(self.vertex_array)
            for corners, texture, depth_texture, weight, (u0, v0, u1, v1), eye, distance in panels:
                GL.glUniform3fv(uniforms["corners"], 4, np.ascontiguousarray(corners, dtype=np.float32))
                GL.glUniform4f(uniforms["uv_rect"], u0, v0, u1, v1)
                GL.glUniform1f(uniforms["impostor_weight"], weight)
                GL.glUniform3f(uniforms["panel_eye"], *(float(v) for v in eye))
                GL.glUniform1f(uniforms["panel_distance"], distance)
                GL.glActiveTexture(GL.GL_TEXTURE2)
                GL.glBindTexture(GL.GL_TEXTURE_2D, depth_texture)
                GL.glActiveTexture(GL.GL_TEXTURE0)
                GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
                GL.glDrawArrays(GL.GL_TRIANGLE_STRIP, 0, 4)
            GL.glBindVertexArray(0)

    def draw_instanced(
        self,
        instances: np.ndarray,
        view_projection: np.ndarray,
        atlas_texture: int,
        *,
        counting: bool = False,
        layer_texture: int | None = None,
        layer_weight: float = 0.0,
        air: tuple[AirVolume, np.ndarray] | None = None,
        shafts: FrameShafts | None = None,
    ) -> None:
        """Depth-tested world-space quads from the impostor atlas in one draw, one instance (`INSTANCE_FLOATS`
        float32, `cloudcore.gl.impostor_atlas.AtlasImage.instance`) a row of `instances`, blended in row
        order; with `layer_texture`, a crossfade: each adds `layer_weight` times that screen layer; with `air`
        (the volume, the eye), seen through it, less the share of that air the frame's light `shafts` take where
        given."""
        crossfade, through_air = layer_texture is not None and not counting, air is not None and not counting
        with_shafts = through_air and shafts is not None
        program = self._atlas_programs[crossfade, counting, through_air, with_shafts]
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_projection"], view_projection)
        self._see_through(program, air, counting)
        if with_shafts:
            shafts.march.bind()
        GL.glUniform1f(uniforms["layer_weight"], float(layer_weight))
        if layer_texture is not None:
            GL.glActiveTexture(GL.GL_TEXTURE1)
            GL.glBindTexture(GL.GL_TEXTURE_2D, layer_texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D_ARRAY, atlas_texture)
        data = np.ascontiguousarray(instances, dtype=np.float32)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._instance_buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, data.nbytes, data, GL.GL_STREAM_DRAW)
        with cloud_blending(True, counting):
            GL.glBindVertexArray(self._instance_array)
            if through_air:
                self._draw_instances_in_cells(uniforms["air_cells"], instances, air[1])
            else:
                GL.glDrawArraysInstanced(GL.GL_TRIANGLE_STRIP, 0, 4, len(data))
            GL.glBindVertexArray(0)

    @staticmethod
    def _draw_instances_in_cells(cells_at: int, instances: np.ndarray, eye: np.ndarray) -> None:
        """The bound instances seen through the air, in two draws that keep their order: those before the first
        that needs more than one cell (`air_cells`) whole, the rest cut as finely as the widest of them needs.
        Sorted far to near, the wide ones are the last few."""
        cells = air_cells(np.asarray(instances, dtype=np.float64)[:, :12], eye)
        first_cut = int(np.argmax(cells > 1)) if np.any(cells > 1) else len(cells)
        _draw_cells(cells_at, 1, first_cut)
        if first_cut < len(cells):
            _draw_cells(cells_at, int(cells[first_cut:].max()), len(cells) - first_cut, first_cut)

    @staticmethod
    def _see_through(program: int, air: tuple[AirVolume, np.ndarray] | None, counting: bool) -> None:
        """Bind the air's volume and the eye for `program` where it draws through the air."""
        if air is None or counting:
            return
        volume, eye = air
        volume.bind(program)
        set_vec3(program, "eye_position", eye)

    def close(self) -> None:
        for program in self._uniforms:
            GL.glDeleteProgram(program)
        GL.glDeleteVertexArrays(2, [self.vertex_array, self._instance_array])
        GL.glDeleteBuffers(1, [self._instance_buffer])


def _draw_cells(cells_at: int, cells: int, count: int, first_instance: int = 0) -> None:
    """Draw `count` quads (instances from `first_instance`, or the one of the uniforms) each cut into `cells` x
    `cells` cells of two triangles (shaders/quad.vert.glsl's AIR)."""
    if count == 0:
        return
    GL.glUniform1i(cells_at, cells)
    GL.glDrawArraysInstancedBaseInstance(GL.GL_TRIANGLES, 0, 6 * cells * cells, count, first_instance)
