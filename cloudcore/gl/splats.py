"""Splats: particles as instanced camera-facing billboards, blended back to front.

`splat_batch` gathers the particles of some clouds (several together, since
clouds interpenetrate in depth), sorts them far to near from the eye, colours
them for that eye (`ParticleShading.seen_from`) and leaves out those the near
fade has made fully transparent; `SplatPass.draw` draws a batch in one
instanced call.  With the depth test on, terrain hides splats; splats never
write depth.  Drawn with `counting=True`, every fragment adds 1 instead
(overdraw).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.eye_scattering import ParticleShading
from cloudcore.gl.blending import cloud_blending
from cloudcore.gl.programs import build_program, set_matrix
from cloudcore.kernel import SPLAT_SHARPNESS

_QUAD_CORNERS = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]], dtype=np.float32)
#: per instance: centre xyz, radius, premultiplied colour rgb, opacity
_INSTANCE_FLOATS = 8


@dataclass(frozen=True)
class SplatBatch:
    instances: np.ndarray  # (n, 8) float32, far to near
    centres: np.ndarray  # (n, 3) float64 world centres, for the analytic overdraw estimate
    radii: np.ndarray

    def __len__(self) -> int:
        return len(self.instances)


def splat_batch(particles: ParticleShading, clouds, eye, depth_ranges=None, time_s: float | None = None) -> SplatBatch:
    """The visible particles of `clouds` (indices), sorted far to near from `eye` and coloured for it.

    `depth_ranges`, one (near, far) per cloud, keeps only the particles with
    near < distance from `eye` <= far: one layer of a cloud split around objects.
    `time_s`, the scene clock, fades forming and dissipating clouds (`ParticleShading.seen_from`).
    """
    starts = particles.cloud_starts
    ranges = [np.arange(starts[c], starts[c + 1]) for c in clouds]
    indices = np.concatenate(ranges) if ranges else np.zeros(0, dtype=np.int64)
    eye = np.asarray(eye, dtype=np.float64)
    distances = np.linalg.norm(particles.centres[indices] - eye, axis=1)
    if depth_ranges is not None:
        near = np.repeat([r[0] for r in depth_ranges], [len(r) for r in ranges])
        far = np.repeat([r[1] for r in depth_ranges], [len(r) for r in ranges])
        kept = (distances > near) & (distances <= far)
        indices, distances = indices[kept], distances[kept]
    far_to_near = indices[np.argsort(-distances, kind="stable")]
    colour, alpha = particles.seen_from(eye, far_to_near, time_s=time_s)
    seen = alpha > 0.0
    drawn = far_to_near[seen]
    instances = np.empty((len(drawn), _INSTANCE_FLOATS), dtype=np.float32)
    instances[:, :3] = particles.centres[drawn]
    instances[:, 3] = particles.radii[drawn]
    instances[:, 4:7] = colour[seen]
    instances[:, 7] = alpha[seen]
    return SplatBatch(instances, particles.centres[drawn], particles.radii[drawn])


class SplatPass:
    def __init__(self):
        self._program = build_program("splat", {"SPLAT_SHARPNESS": SPLAT_SHARPNESS})
        self._counting_program = build_program("splat", {"SPLAT_SHARPNESS": SPLAT_SHARPNESS, "COUNT_FRAGMENTS": 1})
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

    def draw(self, batch: SplatBatch, view: np.ndarray, projection: np.ndarray, *, depth_test: bool = True,
             counting: bool = False) -> None:
        """Blend the batch over the bound target (premultiplied), or add 1 per fragment when counting."""
        if not len(batch):
            return
        program = self._counting_program if counting else self._program
        GL.glUseProgram(program)
        set_matrix(program, "view", view)
        set_matrix(program, "projection", projection)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self._instance_buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, batch.instances.nbytes, batch.instances, GL.GL_STREAM_DRAW)
        with cloud_blending(depth_test, counting):
            GL.glBindVertexArray(self._vertex_array)
            GL.glDrawArraysInstanced(GL.GL_TRIANGLE_STRIP, 0, 4, len(batch))
            GL.glBindVertexArray(0)

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        GL.glDeleteProgram(self._program)
        GL.glDeleteProgram(self._counting_program)
        GL.glDeleteBuffers(2, [self._corner_buffer, self._instance_buffer])
        GL.glDeleteVertexArrays(1, [self._vertex_array])
