"""The cloud pass: every particle as an instanced camera-facing billboard, blended back to front.

Per frame: clouds whose bounding sphere misses the view frustum are dropped,
the remaining particles (of all clouds together, since clouds interpenetrate
in depth) are sorted far to near from the eye, coloured for this eye
(`ParticleShading.seen_from`) and drawn in one instanced call.  The depth
test hides splats behind terrain; splats do not write depth.
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
        instances = np.empty((len(far_to_near), _INSTANCE_FLOATS), dtype=np.float32)
        instances[:, :3] = particles.centres[far_to_near]
        instances[:, 3] = particles.radii[far_to_near]
        instances[:, 4:7] = colour
        instances[:, 7] = alpha
        if len(instances):
            self._draw_instances(instances, view, projection)
        return {"particles_drawn": len(instances), "clouds_drawn": int(visible.sum()),
                "clouds_culled": int((~visible).sum())}

    def _draw_instances(self, instances: np.ndarray, view: np.ndarray, projection: np.ndarray) -> None:
        GL.glUseProgram(self._program)
        set_matrix(self._program, "view", view)
        set_matrix(self._program, "projection", projection)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._instance_buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, instances.nbytes, instances, GL.GL_STREAM_DRAW)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_FALSE)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE_MINUS_SRC_ALPHA)
        GL.glBindVertexArray(self._vertex_array)
        GL.glDrawArraysInstanced(GL.GL_TRIANGLE_STRIP, 0, 4, len(instances))
        GL.glBindVertexArray(0)
        GL.glDisable(GL.GL_BLEND)
        GL.glDepthMask(GL.GL_TRUE)

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        GL.glDeleteProgram(self._program)
        GL.glDeleteBuffers(2, [self._corner_buffer, self._instance_buffer])
        GL.glDeleteVertexArrays(1, [self._vertex_array])
