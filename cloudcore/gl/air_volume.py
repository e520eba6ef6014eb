"""The aerial-perspective volume on the GPU: two 3D float textures (the light the air adds, what it lets through),
uploaded when the volume the frame asks for changes (a new sun, air, or the eye's altitude past its step), and
bound for the passes that draw through the air (shaders/aerial_perspective.glsl)."""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.atmosphere.aerial_perspective import FAR_AIR_FROM, MAX_DISTANCE_M
from cloudcore.gl.programs import set_vec3
from cloudcore.gl.targets import linear_filtering
from cloudcore.light.air_between import AirBetween

#: the texture units of the lookup's samplers, the light added and the transmittance, as
#: shaders/aerial_perspective.glsl declares them
AIR_UNITS = (3, 4)


class AirVolume:
    """The textures of the last volume uploaded; `use` uploads a new one and binds it."""

    def __init__(self):
        self._textures = [int(t) for t in GL.glGenTextures(2)]
        self._volume = None

    def upload(self, air: AirBetween) -> None:
        """Upload `air`'s volume unless it is the one already there."""
        if air.volume is self._volume:
            return
        for texture, values in zip(self._textures, (air.in_scattered(), air.transmittance()), strict=True):
            GL.glBindTexture(GL.GL_TEXTURE_3D, texture)
            linear_filtering(GL.GL_TEXTURE_3D)
            depth, height, width = values.shape[:3]
            pixels = np.ascontiguousarray(values, dtype=np.float32)
            GL.glTexImage3D(GL.GL_TEXTURE_3D, 0, GL.GL_RGB32F, width, height, depth, 0, GL.GL_RGB, GL.GL_FLOAT, pixels)
        GL.glBindTexture(GL.GL_TEXTURE_3D, 0)
        self._volume = air.volume

    def bind(self, program: int) -> None:
        """Bind the textures to `AIR_UNITS` and set the lookup's uniforms of `program` (in use)."""
        for texture, unit in zip(self._textures, AIR_UNITS, strict=True):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_3D, texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        set_vec3(program, "air_sun_direction", self._volume.sun_direction)
        depth, height, width = self._volume.in_scattered.shape[:3]
        set_vec3(program, "air_volume_size", np.array([width, height, depth], dtype=np.float64))
        GL.glUniform1f(GL.glGetUniformLocation(program, "air_max_distance"), MAX_DISTANCE_M)
        # where the terrain's air starts turning into the air to the planet's ground (a program without it ignores it)
        GL.glUniform1f(GL.glGetUniformLocation(program, "far_air_from"), FAR_AIR_FROM * MAX_DISTANCE_M)

    def close(self) -> None:
        GL.glDeleteTextures(self._textures)
