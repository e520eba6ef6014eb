"""The clouds' transmittance map on the GPU: `cloudcore.light.cloud_shadows.opacity_map` drawn from the particles.

Each particle is a square over its disc in the sun's view (shaders/shadow_map.vert.glsl), its optical depth added
into two RGBA32F targets at once, the running sums at the map's eight slices (shadow_map.frag.glsl).  The view is
orthographic, so a point sprite of the square's side covers the square's texels: the map's particles are points
where the largest fits the GL's point sizes (llvmpipe sets up one point for the quad's two triangles, and the
map's making was triangle-bound: docs/performance.md, "A look's parts"), quads otherwise.  The map is
made again only when what it is made of changes: the particle buffer (the clouds, their optics, the lighting) or
the sun's direction, or the texels asked for (a dragged slider's look takes a coarser one); the passes that read it
(the terrain, the objects) bind it with `bind` (shaders/cloud_shadow.glsl).
"""

from __future__ import annotations

import ctypes

import numpy as np
from OpenGL import GL

from cloudcore.gl.programs import build_program, set_matrix
from cloudcore.gl.targets import linear_filtering
from cloudcore.light.cloud_shadows import SLICES, LightSpace, light_space
from cloudcore.maths.splat_kernel import SPLAT_SHARPNESS

#: the texture units of the map's two targets (slices 1-4, 5-8), as shaders/cloud_shadow.glsl declares them
SHADOW_UNITS = (5, 6)
#: floats per particle: centre, radius, opacity (shadow_map.vert.glsl's attributes)
_PARTICLE_FLOATS = 5
if SLICES != 8:
    raise ImportError("shaders/shadow_map.frag.glsl and cloud_shadow.glsl hold eight slices in two RGBA targets")


class CloudShadowMap:
    """The map of the last particles and sun it was made for (`update`); none until then, or without particles."""

    def __init__(self):
        defines = {"SPLAT_SHARPNESS": SPLAT_SHARPNESS}
        #: (the quads' program, the points')
        self._programs = (build_program("shadow_map", defines), build_program("shadow_map", defines | {"POINTS": 1}))
        self._largest_point = float(GL.glGetFloatv(GL.GL_POINT_SIZE_RANGE)[1])
        self._buffer = GL.glGenBuffers(1)
        #: (the quads' vertex array: a particle an instance of four corners, the points': a particle a vertex, which
        #: llvmpipe draws faster than an instance of one point: docs/performance.md, "The drag at 4 looks a second")
        self._vertex_arrays = tuple(int(v) for v in GL.glGenVertexArrays(2))
        for vertex_array, divisor in zip(self._vertex_arrays, (1, 0)):
            GL.glBindVertexArray(vertex_array)
            GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._buffer)
            for location, floats, offset in ((0, 3, 0), (1, 1, 3), (2, 1, 4)):
                GL.glEnableVertexAttribArray(location)
                GL.glVertexAttribPointer(
                    location, floats, GL.GL_FLOAT, GL.GL_FALSE, 4 * _PARTICLE_FLOATS, ctypes.c_void_p(4 * offset)
                )
                GL.glVertexAttribDivisor(location, divisor)
        GL.glBindVertexArray(0)
        self._framebuffer = GL.glGenFramebuffers(1)
        self._textures: list[int] = []
        self._texture_size: tuple[int, int] | None = None
        self._source = None
        self._made_space: LightSpace | None = None  # the view the map was drawn in
        #: the view the map is read in (the one it was drawn in, moved with the clouds), None while there is no map
        self.space: LightSpace | None = None
        self.made = 0  # how many times a map was made
        self.drawn_as_points = False  # whether the last map made drew its particles as point sprites

    def update(
        self,
        particles,
        sun_direction,
        resolution: int,
        opacity_factors=None,
        factors_key=None,
        shift=(0.0, 0.0, 0.0),
    ) -> None:
        """Make the map of `particles` (a `ParticleBuffer`, each particle's opacity times its `opacity_factors`
        where given: the clouds' formations, a field's blend weights) seen from `sun_direction` (toward the sun) at
        `resolution` texels across, unless it is the one held (the same buffer, sun, resolution and `factors_key`,
        which names the factors), and read it as the map of those particles all moved by `shift` (3,) metres: the
        wind drifting every cloud alike moves their shadows without making the map again (`LightSpace.moved`)."""
        sun = tuple(float(v) for v in sun_direction)
        source = (particles, sun, resolution, factors_key)
        if self._source is None or self._source[0] is not particles or self._source[1:] != source[1:]:
            self._source = source
            self._made_space = light_space(particles.centres, particles.radii, sun, resolution)
            if self._made_space is not None:
                opacity = particles.alpha if opacity_factors is None else particles.alpha * opacity_factors
                self._draw(particles, opacity, self._made_space)
                self.made += 1
        self.space = None if self._made_space is None else self._made_space.moved(shift)

    def _draw(self, particles, opacity, space: LightSpace) -> None:
        # the ground's and the objects' shadow takes each particle's whole opacity out of the sun's beam: nearer the
        # path-traced truth's shadows than the light pass's beam opacity (docs/atmosphere.md#cloud-shadows)
        instances = np.column_stack([particles.centres, particles.radii, opacity]).astype(np.float32)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, instances.nbytes, np.ascontiguousarray(instances), GL.GL_STATIC_DRAW)
        self._bind_targets(space.size)
        width, height = space.size
        GL.glViewport(0, 0, width, height)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        # a particle's square is 2 max(radius, texel) across (shadow_map.vert.glsl)
        points = 2.0 * max(float(particles.radii.max()), space.texel_m) / space.texel_m <= self._largest_point
        self.drawn_as_points = points
        program = self._programs[points]
        GL.glUseProgram(program)
        set_matrix(program, "world_to_map", space.world_to_map())
        GL.glUniform1f(GL.glGetUniformLocation(program, "texel_m"), space.texel_m)
        GL.glUniform2f(GL.glGetUniformLocation(program, "map_size"), float(width), float(height))
        GL.glUniform1f(GL.glGetUniformLocation(program, "slice_m"), space.slice_m)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE)
        GL.glBindVertexArray(self._vertex_arrays[points])
        if points:
            GL.glEnable(GL.GL_PROGRAM_POINT_SIZE)
            GL.glDrawArrays(GL.GL_POINTS, 0, len(instances))
            GL.glDisable(GL.GL_PROGRAM_POINT_SIZE)
        else:
            GL.glDrawArraysInstanced(GL.GL_TRIANGLE_STRIP, 0, 4, len(instances))
        GL.glBindVertexArray(0)
        GL.glDisable(GL.GL_BLEND)

    def _bind_targets(self, size: tuple[int, int]) -> None:
        """Bind the framebuffer with both targets, of `size` (made again when it changes)."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._framebuffer)
        if size != self._texture_size:
            if self._textures:
                GL.glDeleteTextures(self._textures)
            self._textures = [int(t) for t in GL.glGenTextures(2)]
            for attachment, texture in enumerate(self._textures):
                GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
                GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_RGBA32F, *size)
                linear_filtering(GL.GL_TEXTURE_2D, GL.GL_CLAMP_TO_BORDER)
                # off the map no cloud is in front: no optical depth
                GL.glTexParameterfv(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_BORDER_COLOR, np.zeros(4, dtype=np.float32))
                GL.glFramebufferTexture2D(
                    GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0 + attachment, GL.GL_TEXTURE_2D, texture, 0
                )
            GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
            status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
            if status != GL.GL_FRAMEBUFFER_COMPLETE:
                raise RuntimeError(f"cloud shadow map framebuffer incomplete (status 0x{int(status):x})")
            self._texture_size = size
        GL.glDrawBuffers(2, [GL.GL_COLOR_ATTACHMENT0, GL.GL_COLOR_ATTACHMENT1])

    def bind(self, program: int) -> None:
        """Set `program`'s (in use) cloud_shadow.glsl uniforms: the map's textures and view, or no shadows."""
        GL.glUniform1i(GL.glGetUniformLocation(program, "cloud_shadows"), int(self.space is not None))
        if self.space is None:
            return
        for texture, unit in zip(self._textures, SHADOW_UNITS, strict=True):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        set_matrix(program, "world_to_cloud_shadow", self.space.world_to_map())

    def read(self) -> np.ndarray:
        """(SLICES, height, width) float64: the map's optical depths, as `opacity_map` gives them (for tests)."""
        width, height = self.space.size
        slices = []
        for texture in self._textures:
            GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
            pixels = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_RGBA, GL.GL_FLOAT)
            slices.append(np.frombuffer(pixels, dtype=np.float32).reshape(height, width, 4))
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        return np.moveaxis(np.concatenate(slices, axis=2), 2, 0).astype(np.float64)

    def close(self) -> None:
        if self._textures:
            GL.glDeleteTextures(self._textures)
        GL.glDeleteFramebuffers(1, [self._framebuffer])
        GL.glDeleteBuffers(1, [self._buffer])
        GL.glDeleteVertexArrays(2, list(self._vertex_arrays))
        for program in self._programs:
            GL.glDeleteProgram(program)
