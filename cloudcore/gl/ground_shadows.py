"""The clouds' shadow on the ground baked on the GPU: the texture `cloudcore.light.ground_shadows` lays out, which
the terrain's pixels read with one fetch instead of the clouds' map (shaders/terrain.frag.glsl).

The terrain's tiles are drawn from above into the texture (shaders/ground_shadow_bake.*.glsl), each texel the
share of the sun the map lets reach the ground there; the ground under no tile drawn is clear.  When, and which
tiles: `cloudcore.light.ground_shadows.BakePlan` (`TerrainMesh.bake_ground_shadows` follows it).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from OpenGL import GL

from cloudcore.gl.programs import ProgramCache, set_matrix
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.targets import TextureTarget
from cloudcore.light.ground_shadows import GroundShadowFrame

#: the texture unit of the baked texture, as shaders/terrain.frag.glsl declares it
GROUND_SHADOW_UNIT = 9


class GroundShadows:
    """The texture of the last bake (`bake`); none before it."""

    def __init__(self, programs: ProgramCache):
        self._programs = programs  # the world pass's
        self._target: TextureTarget | None = None
        self.frame: GroundShadowFrame | None = None
        self.baked = 0  # how many times a texture was baked

    def bake(
        self, frame: GroundShadowFrame, shadows: CloudShadowMap, draw_ground: Callable[[], None], afresh: bool
    ) -> None:
        """Bake the clouds' `shadows` on the ground that `draw_ground()` draws (its positions at attribute 0) into
        the texture of `frame`: `afresh`, cleared first; else over what it holds (of the same `frame`).  Leaves the
        texture's framebuffer bound."""
        if self._target is None or (self._target.width, self._target.height) != frame.size:
            if self._target is not None:
                self._target.close()
            self._target = TextureTarget(*frame.size, GL.GL_RGBA8)
        self._target.bind()
        if afresh:
            GL.glClearColor(1.0, 1.0, 1.0, 1.0)  # the ground under no tile drawn: nothing reads it but its edge
            GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        program = self._programs.program("ground_shadow_bake")
        GL.glUseProgram(program)
        shadows.bind(program)
        set_matrix(program, "world_to_ground_shadow", frame.world_to_texture())
        # a heightfield's tiles do not overlap seen from above (their skirts hang straight down: no texels)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDisable(GL.GL_BLEND)
        draw_ground()
        self.frame = frame
        self.baked += 1

    def bind(self, program: int) -> None:
        """Bind the texture for `program` (in use) with its frame's matrix (shaders/terrain.*.glsl)."""
        GL.glActiveTexture(GL.GL_TEXTURE0 + GROUND_SHADOW_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._target.texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        set_matrix(program, "world_to_ground_shadow", self.frame.world_to_texture())

    def read(self) -> np.ndarray:
        """(across, along) float: the baked share at each texel, row j (v) first (for tests)."""
        return self._target.read()[::-1, :, 0]

    def close(self) -> None:
        if self._target is not None:
            self._target.close()
