"""The cloud pass drawn at a fraction of the screen's resolution and laid over the world by a depth-aware upsampling
(Yusov 2014, section 5.4; what it tests against and how a pixel picks its texels: `cloudcore.maths.depth_upsampling`).

`ReducedClouds.begin` fills the reduced pass's depth with the nearest world depth of each block of the screen's
pixels and clears its colour; the frame's cloud draws (splats, impostors, ring panels, crossfades, screen impostors'
composites) then go into it as they would into the screen, and `composite` lays what they drew over the frame at
full resolution, on the tiles of the screen that hold cloud.  Objects between cloud layers (Harris 3.1.1) are drawn
at full resolution between two composites: `composite`, the object, `resume`.
"""

from __future__ import annotations

import math

import numpy as np
from OpenGL import GL

from cloudcore.gl.programs import build_program, uniform_locations
from cloudcore.gl.targets import DepthTexture, TextureTarget
from cloudcore.maths.depth_upsampling import BEHIND_TOLERANCE, DEPTH_TOLERANCE, NO_MATCH_WEIGHT
from cloudcore.world.camera import FAR_PLANE_M, NEAR_PLANE_M

#: the side of the composite's tiles, in screen pixels: llvmpipe's own tiles, whose loading and storing a draw pays
#: for each it touches
TILE_PIXELS = 64
_SIZES = ("screen_size", "reduced_size", "tile_pixels")


class ReducedClouds:
    """The reduced pass's targets (colour, depth, a crossfade layer sharing its depth), remade for another size, and
    the full-screen passes that fill its depth, find the tiles it covers and composite it.  Needs a current
    context."""

    def __init__(self):
        self._block_depth = build_program("block_depth", vertex="world")
        self._tiles = build_program("cloud_tiles", vertex="world")
        self._upsample = build_program("cloud_upsample", vertex="cloud_tiles")
        GL.glUseProgram(self._upsample)
        for unit, name in enumerate(("clouds", "cloud_depth", "world_depth", "tiles_covered")):
            GL.glUniform1i(GL.glGetUniformLocation(self._upsample, name), unit)
        for name, value in (
            ("near_m", NEAR_PLANE_M),
            ("far_m", FAR_PLANE_M),
            ("tolerance", DEPTH_TOLERANCE),
            ("behind_tolerance", BEHIND_TOLERANCE),
            ("no_match_weight", NO_MATCH_WEIGHT),
        ):
            GL.glUniform1f(GL.glGetUniformLocation(self._upsample, name), value)
        self._sizes = {
            program: uniform_locations(program, _SIZES) for program in (self._block_depth, self._tiles, self._upsample)
        }
        self._vertex_array = GL.glGenVertexArrays(1)  # core profile draws nothing without one
        self._world_depth = DepthTexture()  # the screen's depth, which the shaders read
        self._depth = DepthTexture()  # the reduced pass's
        self.target: TextureTarget | None = None
        self._layer: TextureTarget | None = None
        self._covered: TextureTarget | None = None  # a texel a tile of the screen: 1 where it holds cloud
        self._screen_size = (0, 0)

    @property
    def size(self) -> tuple[int, int]:
        return self.target.width, self.target.height

    def begin(self, context, size: tuple[int, int]) -> None:
        """Start the reduced pass of `size` for `context`'s frame (its world drawn): its depth the nearest of each
        block of the world's, its colour clear, bound for drawing."""
        screen = (context.width, context.height)
        if screen != self._screen_size:
            self._screen_size = screen
            if self._covered is not None:
                self._covered.close()
            tiles = tuple(math.ceil(side / TILE_PIXELS) for side in screen)
            self._covered = TextureTarget(*tiles, GL.GL_R8)
        world_depth = self._world_depth.copy(context.framebuffer, screen)
        self._depth.bind_cleared(size)  # remade for another size: the targets sharing it are too
        if self.target is None or self.size != tuple(size):
            self._close_targets()
            self.target = TextureTarget(*size, depth_texture=self._depth.texture)
            GL.glBindTexture(GL.GL_TEXTURE_2D, self._depth.texture)  # the upsampling gathers it at its edges too
            for axis in (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T):
                GL.glTexParameteri(GL.GL_TEXTURE_2D, axis, GL.GL_CLAMP_TO_EDGE)
            self._depth.bind_cleared(size)
        self._use(self._block_depth, (world_depth,))
        GL.glEnable(GL.GL_DEPTH_TEST)  # every texel's depth written, whatever was there
        GL.glDepthFunc(GL.GL_ALWAYS)
        GL.glDepthMask(GL.GL_TRUE)
        self._draw(1)
        GL.glDepthFunc(GL.GL_LESS)
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
        world's depth, on the tiles of the screen it covers; leaves the frame bound."""
        self._covered.bind()
        self._use(self._tiles, (self.target.texture,))
        GL.glDisable(GL.GL_DEPTH_TEST)
        self._draw(1)
        context.bind_target()
        self._use(
            self._upsample,
            (self.target.texture, self._depth.texture, self._world_depth.texture, self._covered.texture),
        )
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE_MINUS_SRC_ALPHA)
        self._draw(self._covered.width * self._covered.height)
        GL.glDisable(GL.GL_BLEND)

    def _use(self, program: int, textures) -> None:
        """Make `program` current with the sizes and `textures` on units 0, 1, ...; the viewport of the bound
        target is the caller's."""
        GL.glUseProgram(program)
        locations = self._sizes[program]
        GL.glUniform2i(locations["screen_size"], *self._screen_size)
        GL.glUniform2i(locations["reduced_size"], *self.size)
        GL.glUniform1i(locations["tile_pixels"], TILE_PIXELS)
        for unit, texture in enumerate(textures):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)

    def _draw(self, instances: int) -> None:
        """The screen triangle of world.vert (one instance), or the tiles of cloud_tiles.vert."""
        GL.glBindVertexArray(self._vertex_array)
        if instances == 1:
            GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        else:
            GL.glDrawArraysInstanced(GL.GL_TRIANGLE_STRIP, 0, 4, instances)
        GL.glBindVertexArray(0)

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """(its colour (h, w, 4), the depth it was tested against (h, w)) as float32, bottom row first (GL's order,
        `cloudcore.maths.depth_upsampling`'s): what the last composite laid over the screen, for tests."""
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._depth.texture)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        depth = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
        width, height = self.size
        depth = np.frombuffer(depth, dtype=np.float32).reshape(height, width)
        return self.target.read()[::-1].copy(), depth.copy()

    @property
    def nbytes(self) -> int:
        """GPU memory of its colour targets."""
        return sum(target.nbytes for target in (self.target, self._layer, self._covered) if target is not None)

    def _close_targets(self) -> None:
        for target in (self.target, self._layer):
            if target is not None:
                target.close()
        self.target = self._layer = None

    def close(self) -> None:
        self._close_targets()
        if self._covered is not None:
            self._covered.close()
        self._world_depth.close()
        self._depth.close()
        for program in (self._block_depth, self._tiles, self._upsample):
            GL.glDeleteProgram(program)
        GL.glDeleteVertexArrays(1, [self._vertex_array])
