"""The cloud pass drawn at a fraction of the screen's resolution and laid over the world by a depth-aware upsampling
(Yusov 2014, section 5.4; what it tests against and how a pixel picks its texels: `cloudcore.depth_upsampling`).

`ReducedClouds.begin` fills the reduced pass's depth with the nearest world depth of each block of the screen's
pixels and clears its colour; the frame's cloud draws (splats, impostors, ring panels, crossfades, screen impostors'
composites) then go into it as they would into the screen, and `composite` lays what they drew over the frame at
full resolution.  Objects between cloud layers (Harris 3.1.1) are drawn at full resolution between two composites:
`composite`, the object, `resume`.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.camera import FAR_PLANE_M, NEAR_PLANE_M
from cloudcore.depth_upsampling import BEHIND_TOLERANCE, DEPTH_TOLERANCE, NO_MATCH_WEIGHT
from cloudcore.gl.programs import build_program, uniform_locations
from cloudcore.gl.targets import DepthTexture, TextureTarget

_SCREEN_SIZES = ("screen_size", "reduced_size")


class ReducedClouds:
    """The reduced pass's targets (colour, depth, a crossfade layer sharing its depth), remade for another size, and
    the two full-screen passes that fill its depth and composite it.  Needs a current context."""

    def __init__(self):
        self._block_depth = build_program("block_depth", vertex="world")
        self._upsample = build_program("cloud_upsample", vertex="world")
        GL.glUseProgram(self._upsample)
        for unit, name in enumerate(("clouds", "cloud_depth", "world_depth")):
            GL.glUniform1i(GL.glGetUniformLocation(self._upsample, name), unit)
        GL.glUniform1f(GL.glGetUniformLocation(self._upsample, "near_m"), NEAR_PLANE_M)
        GL.glUniform1f(GL.glGetUniformLocation(self._upsample, "far_m"), FAR_PLANE_M)
        GL.glUniform1f(GL.glGetUniformLocation(self._upsample, "tolerance"), DEPTH_TOLERANCE)
        GL.glUniform1f(GL.glGetUniformLocation(self._upsample, "behind_tolerance"), BEHIND_TOLERANCE)
        GL.glUniform1f(GL.glGetUniformLocation(self._upsample, "no_match_weight"), NO_MATCH_WEIGHT)
        self._sizes = {
            program: uniform_locations(program, _SCREEN_SIZES) for program in (self._block_depth, self._upsample)
        }
        self._vertex_array = GL.glGenVertexArrays(1)  # core profile draws nothing without one
        self._world_depth = DepthTexture()  # the screen's depth, which the shaders read
        self._depth = DepthTexture()  # the reduced pass's
        self.target: TextureTarget | None = None
        self._layer: TextureTarget | None = None
        self._screen_size = (0, 0)

    @property
    def size(self) -> tuple[int, int]:
        return self.target.width, self.target.height

    def begin(self, context, size: tuple[int, int]) -> None:
        """Start the reduced pass of `size` for `context`'s frame (its world drawn): its depth the nearest of each
        block of the world's, its colour clear, bound for drawing."""
        screen = (context.width, context.height)
        self._screen_size = screen
        world_depth = self._world_depth.copy(context.framebuffer, screen)
        self._depth.bind_cleared(size)  # remade for another size: the targets sharing it are too
        if self.target is None or self.size != tuple(size):
            self._close_targets()
            self.target = TextureTarget(*size, depth_texture=self._depth.texture)
            self._depth.bind_cleared(size)
        self._draw_screen_triangle(self._block_depth, (world_depth,), size)
        self.resume()

    def resume(self) -> None:
        """Draw into the reduced pass from now on, its colour clear (its depth kept)."""
        self.target.bind_cleared()

    def bind(self) -> None:
        """Draw into the reduced pass from now on, over what it holds."""
        self.target.bind()

    def layer(self) -> TextureTarget:
        """A layer of the reduced pass's size sharing its depth: a crossfading unit's full-3D image."""
        if self._layer is None:
            self._layer = TextureTarget(*self.size, depth_texture=self._depth.texture)
        return self._layer

    def composite(self, context) -> None:
        """Blend what the reduced pass drew since it began or resumed over `context`'s frame, upsampled against the
        world's depth; leaves the frame bound."""
        context.bind_target()
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE_MINUS_SRC_ALPHA)
        textures = (self.target.texture, self._depth.texture, self._world_depth.texture)
        self._draw_screen_triangle(self._upsample, textures, self._screen_size)
        GL.glDisable(GL.GL_BLEND)

    def _draw_screen_triangle(self, program: int, textures, viewport) -> None:
        """`program` over the bound target's `viewport`, `textures` on units 0, 1, ..., no depth test unless it
        writes the depth (block_depth: every texel's, whatever was there)."""
        GL.glUseProgram(program)
        locations = self._sizes[program]
        GL.glUniform2i(locations["screen_size"], *self._screen_size)
        GL.glUniform2i(locations["reduced_size"], *self.size)
        for unit, texture in enumerate(textures):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        writes_depth = program == self._block_depth
        GL.glViewport(0, 0, *viewport)
        GL.glDisable(GL.GL_SCISSOR_TEST)
        if writes_depth:
            GL.glEnable(GL.GL_DEPTH_TEST)
            GL.glDepthFunc(GL.GL_ALWAYS)
            GL.glDepthMask(GL.GL_TRUE)
        else:
            GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glBindVertexArray(self._vertex_array)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glBindVertexArray(0)
        GL.glDepthFunc(GL.GL_LESS)

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """(its colour (h, w, 4), the depth it was tested against (h, w)) as float32, bottom row first (GL's order,
        `cloudcore.depth_upsampling`'s): what the last composite laid over the screen, for tests."""
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._depth.texture)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        depth = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
        width, height = self.size
        depth = np.frombuffer(depth, dtype=np.float32).reshape(height, width)
        return self.target.read()[::-1].copy(), depth.copy()

    @property
    def nbytes(self) -> int:
        """GPU memory of its colour targets."""
        return sum(target.nbytes for target in (self.target, self._layer) if target is not None)

    def _close_targets(self) -> None:
        for target in (self.target, self._layer):
            if target is not None:
                target.close()
        self.target = self._layer = None

    def close(self) -> None:
        self._close_targets()
        self._world_depth.close()
        self._depth.close()
        for program in (self._block_depth, self._upsample):
            GL.glDeleteProgram(program)
        GL.glDeleteVertexArrays(1, [self._vertex_array])
