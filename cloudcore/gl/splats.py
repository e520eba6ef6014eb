"""The cloud pass: every particle as an instanced camera-facing billboard, blended back to front.

Per frame: clouds whose bounding sphere misses the view frustum are dropped,
the remaining particles (of all clouds together, since clouds interpenetrate
in depth) are sorted far to near from the eye, coloured for this eye
(`ParticleShading.seen_from`) and drawn in one instanced call; particles the
near fade has made fully transparent are left out.  The depth test hides
splats behind terrain; splats do not write depth.  `count_fragments` replays
the last draw with a shader that writes 1 per fragment, for overdraw.
"""

from __future__ import annotations

import ctypes

import numpy as np
from OpenGL import GL

from cloudcore.camera import frustum_planes, spheres_in_frustum
from cloudcore.eye_scattering import ParticleShading
from cloudcore.gl.programs import build_program, set_matrix
from cloudcore.kernel import SPLAT_SHARPNESS

_QUAD_CORNERS = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]], dtype=np.float32)
#: per instance: centre xyz, radius, premultiplied colour rgb, opacity
_INSTANCE_FLOATS = 8


class SplatPass:
    def __init__(self):
        self._program = build_program("splat", {"SPLAT_SHARPNESS": SPLAT_SHARPNESS})
        self._counting_program = build_program("splat", {"SPLAT_SHARPNESS": SPLAT_SHARPNESS, "COUNT_FRAGMENTS": 1})
        self._instance_count = 0
        #: the last draw's particles (world centres, radii), for the analytic overdraw estimate
        self.drawn_centres, self.drawn_radii = np.zeros((0, 3)), np.zeros(0)
        self._vertex_array = GL.glGenVertexArrays(1)
        self._corner_buffer, self._instance_buffer = GL.glGenBuffers(2)
        GL.glBindVertexArray(self._vertex_array)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._corner_buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, _QUAD_CORNERS.nbytes, _QUAD_CORNERS, GL.GL_STATIC_DRAW)
        GL.glEnableVertexAttribArray(0)
        GL.glVertexAttribPointer(0, 2, GL.GL_FLOAT, GL.GL_FALSE, 0, ctypes.c_void_p(0))
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._instance_buffer)
        stride = _INSTANCE_FLOATS * 4
        for location, offset in ((1, 0), (2, 16)):
            GL.glEnableVertexAttribArray(location)
            GL.glVertexAttribPointer(location, 4, GL.GL_FLOAT, GL.GL_FALSE, stride, ctypes.c_void_p(offset))
            GL.glVertexAttribDivisor(location, 1)
        GL.glBindVertexArray(0)

    def draw(self, particles: ParticleShading, eye, view: np.ndarray, projection: np.ndarray) -> dict:
        """Draw the visible clouds into the bound target; returns the culling counts."""
        view_projection = projection @ view
        visible = spheres_in_frustum(frustum_planes(view_projection),
                                     particles.bounding_centres, particles.bounding_radii)
        starts = particles.cloud_starts
        ranges = [np.arange(starts[c], starts[c + 1]) for c in np.flatnonzero(visible)]
        indices = np.concatenate(ranges) if ranges else np.zeros(0, dtype=np.int64)
        eye = np.asarray(eye, dtype=np.float64)
        far_to_near = indices[np.argsort(-np.linalg.norm(particles.centres[indices] - eye, axis=1))]
        colour, alpha = particles.seen_from(eye, far_to_near)
        seen = alpha > 0.0
        drawn = far_to_near[seen]
        instances = np.empty((len(drawn), _INSTANCE_FLOATS), dtype=np.float32)
        instances[:, :3] = particles.centres[drawn]
        instances[:, 3] = particles.radii[drawn]
        instances[:, 4:7] = colour[seen]
        instances[:, 7] = alpha[seen]
        self._instance_count = len(instances)
        self.drawn_centres, self.drawn_radii = particles.centres[drawn], particles.radii[drawn]
        if len(instances):
            GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._instance_buffer)
            GL.glBufferData(GL.GL_ARRAY_BUFFER, instances.nbytes, instances, GL.GL_STREAM_DRAW)
            self._draw_instances(self._program, view, projection)
        return {"particles_drawn": len(instances), "clouds_drawn": int(visible.sum()),
                "clouds_culled": int((~visible).sum())}

    def count_fragments(self, view: np.ndarray, projection: np.ndarray) -> None:
        """Redraw the last frame's splats adding 1 per fragment into the bound (float) target."""
        if self._instance_count:
            self._draw_instances(self._counting_program, view, projection, additive=True)

    def _draw_instances(self, program: int, view: np.ndarray, projection: np.ndarray, additive=False) -> None:
        GL.glUseProgram(program)
        set_matrix(program, "view", view)
        set_matrix(program, "projection", projection)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_FALSE)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE if additive else GL.GL_ONE_MINUS_SRC_ALPHA)
        GL.glBindVertexArray(self._vertex_array)
        GL.glDrawArraysInstanced(GL.GL_TRIANGLE_STRIP, 0, 4, self._instance_count)
        GL.glBindVertexArray(0)
        GL.glDisable(GL.GL_BLEND)
        GL.glDepthMask(GL.GL_TRUE)

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        GL.glDeleteProgram(self._program)
        GL.glDeleteProgram(self._counting_program)
        GL.glDeleteBuffers(2, [self._corner_buffer, self._instance_buffer])
        GL.glDeleteVertexArrays(1, [self._vertex_array])
