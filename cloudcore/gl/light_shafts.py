"""Light shafts on the GPU: the air's light the clouds' shadow keeps from the eye, marched at a fraction of the
screen's resolution before the world is drawn (shaders/light_shafts.frag.glsl, `cloudcore.light.light_shafts`'
twin, up to the terrain's depth drawn at that resolution), then taken off by the sky per pixel and, as a share of
its air's light, by the terrain per vertex as they are drawn (shaders/light_shafts_read.glsl): a pass of its own
over the screen's pixels, or the terrain's lookup per pixel, cost llvmpipe more than the march
(docs/atmosphere.md#light-shafts)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.programs import ProgramCache, set_matrix, set_vec3
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.targets import DepthTexture, TextureTarget
from cloudcore.light.light_shafts import SHAFT_STEPS
from cloudcore.model.scene import Camera

#: the march's columns, about: its error against a fine march is set by how many rays it has, not by the screen's
#: pixels, and its cost with them (docs/atmosphere.md#light-shafts)
SHAFT_COLUMNS = 80
#: the texture unit of the march's target, as shaders/light_shafts_read.glsl declares it
SHAFTS_UNIT = 7


def shaft_reduction(width: int) -> int:
    """Screen pixels a shaft pixel spans, per axis, for a frame `width` pixels wide: about `SHAFT_COLUMNS`
    columns."""
    return max(1, round(width / SHAFT_COLUMNS))


def shaft_size(width: int, height: int, reduction: int) -> tuple[int, int]:
    """The march's (width, height) for a frame of `width` x `height`: a pixel for each `reduction`-square block,
    each seeing the same view."""
    return -(-width // reduction), -(-height // reduction)


@dataclass(frozen=True, eq=False)
class FrameShafts:
    """A frame's march, marched up to the clouds' nearest distance (Yusov's cut), for the clouds' shaders to read:
    each cloud's own air scaled by the share the shadows leave of the air in front of it, as the terrain's is,
    whichever representation draws it (docs/atmosphere.md#the-shafts-and-the-air-in-front-of-the-clouds)."""

    march: LightShaftPass
    #: the frame's projection times its view's rotation: points relative to the eye onto the march's target
    eye_view_projection: np.ndarray

    def bind(self, program: int) -> None:
        """Bind the march's target (`SHAFTS_UNIT`) and set `program`'s (in use) `shaft_view_projection`."""
        self.march.bind()
        set_matrix(program, "shaft_view_projection", self.eye_view_projection)


class LightShaftPass:
    """The march's targets and program; `march` fills them, `bind` lets the terrain's and the sky's programs read
    them."""

    def __init__(self, steps: int = SHAFT_STEPS, reduction: int | None = None, programs: ProgramCache | None = None):
        """`steps` along each ray, a shaft pixel for each `reduction`-square block of the screen's, by default
        `shaft_reduction`'s (the benchmark of the choice tries others: scripts/bench_light_shafts.py); the programs
        from `programs` (the caller's, which it closes), else its own."""
        self._steps, self._reduction = steps, reduction
        self._own_programs = programs is None
        self._programs = ProgramCache() if programs is None else programs
        self._program = self._programs.program("light_shafts", vertex="world")
        self._blur_program = self._programs.program("light_shafts_blur", vertex="world")
        self._depth = DepthTexture()
        self._targets: tuple[TextureTarget, TextureTarget] | None = None  # the march's, and its blurred
        # core profile draws nothing without a vertex array, even one with no attributes
        self._fullscreen_vertex_array = GL.glGenVertexArrays(1)

    def march(
        self,
        screen_size: tuple[int, int],
        draw_terrain_depth: Callable[[], None] | None,
        camera: Camera,
        view: np.ndarray,
        projection: np.ndarray,
        air: AirVolume,
        shadows: CloudShadowMap,
        sky_lowest_up: float,
        planet_ground: tuple[float, float] | None = None,
        draw_cloud_depth: Callable[[tuple[int, int]], None] | None = None,
    ) -> None:
        """March the shafts of `shadows` in `air` (bound for `camera`'s eye) for a frame of `screen_size` seen
        through `view` and `projection`, up to the depth `draw_terrain_depth` draws (nothing: the sky everywhere),
        the sky's rays below `sky_lowest_up` (a cosine to the up) marched at it, as the sky draws them; or, where
        the sky draws the planet's ground past the terrain, `planet_ground` (the eye's altitude over it, its
        radius; metres), up to that ground; and up to the clouds' nearest depth that `draw_cloud_depth(size)` draws
        at the march's size where given (Yusov's cut: `FrameShafts`).  Leaves the framebuffer of the march bound:
        the caller binds its own."""
        reduction = shaft_reduction(screen_size[0]) if self._reduction is None else self._reduction
        size = shaft_size(*screen_size, reduction)
        self._depth.bind_cleared(size)
        if draw_terrain_depth is not None:
            draw_terrain_depth()
        if draw_cloud_depth is not None:
            draw_cloud_depth(size)
        march, blurred = self._targets_of(size)
        march.bind()
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDisable(GL.GL_BLEND)
        program = self._program
        GL.glUseProgram(program)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._depth.texture)
        set_vec3(program, "eye_position", camera.position)
        set_vec3(program, "view_right", view[0, :3])
        set_vec3(program, "view_up", view[1, :3])
        set_vec3(program, "view_forward", -view[2, :3])
        GL.glUniform2f(GL.glGetUniformLocation(program, "focal"), projection[0, 0], projection[1, 1])
        GL.glUniform2f(GL.glGetUniformLocation(program, "depth_terms"), projection[2, 2], projection[2, 3])
        GL.glUniform1i(GL.glGetUniformLocation(program, "steps"), self._steps)
        GL.glUniform1f(GL.glGetUniformLocation(program, "sky_lowest_up"), sky_lowest_up)
        GL.glUniform2f(GL.glGetUniformLocation(program, "planet_ground"), *(planet_ground or (-1.0, 0.0)))
        air.bind(program)
        shadows.bind(program)
        GL.glBindVertexArray(self._fullscreen_vertex_array)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        blurred.bind()
        GL.glUseProgram(self._blur_program)
        GL.glBindTexture(GL.GL_TEXTURE_2D, march.texture)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glBindVertexArray(0)
        GL.glEnable(GL.GL_DEPTH_TEST)

    def bind(self) -> None:
        """Bind the last march's target for shaders/light_shafts_read.glsl."""
        GL.glActiveTexture(GL.GL_TEXTURE0 + SHAFTS_UNIT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._targets[1].texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)

    def read(self, blurred: bool = True) -> np.ndarray:
        """The last march's (height, width, 4) target, top row first, blurred as the world reads it or not: the
        air's light taken, its share (tests)."""
        return self._targets[int(blurred)].read()

    def read_depth(self) -> np.ndarray:
        """The terrain's window depths (height, width) the last march read, top row first (tests)."""
        return self._depth.read()

    def _targets_of(self, size: tuple[int, int]) -> tuple[TextureTarget, TextureTarget]:
        if self._targets is None or (self._targets[0].width, self._targets[0].height) != size:
            self._close_targets()
            self._targets = (TextureTarget(*size, GL.GL_RGBA16F), TextureTarget(*size, GL.GL_RGBA16F))
        return self._targets

    def _close_targets(self) -> None:
        if self._targets is not None:
            for target in self._targets:
                target.close()
        self._targets = None

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        self._depth.close()
        self._close_targets()
        if self._own_programs:
            self._programs.close()
        GL.glDeleteVertexArrays(1, [self._fullscreen_vertex_array])
