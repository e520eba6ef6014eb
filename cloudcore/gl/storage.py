"""Shader storage buffers: filled from numpy, grown as scratch space, bound, copied."""

from __future__ import annotations

import numpy as np
from OpenGL import GL


def store(buffer: int, data: np.ndarray, usage=GL.GL_STATIC_DRAW) -> None:
    """Fill storage buffer `buffer` with `data` (its size becomes the data's)."""
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
    GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, data.nbytes, np.ascontiguousarray(data), usage)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)


def reallocate_storage(buffers, size: int) -> None:
    """Give each storage buffer of `buffers` `size` bytes, its contents undefined (scratch space that grows)."""
    for buffer in buffers:
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, size, None, GL.GL_DYNAMIC_COPY)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)


def bind_storage(*bindings) -> None:
    """Bind each (binding point, buffer) pair as a shader storage buffer."""
    for binding, buffer in bindings:
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, binding, buffer)


def copy_buffer(source: int, destination: int, size: int, allocate: bool) -> None:
    """Copy the first `size` bytes of buffer `source` into `destination` (first given that size: `allocate`)."""
    GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, source)
    GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, destination)
    if allocate:
        GL.glBufferData(GL.GL_COPY_WRITE_BUFFER, size, None, GL.GL_STREAM_COPY)
    GL.glCopyBufferSubData(GL.GL_COPY_READ_BUFFER, GL.GL_COPY_WRITE_BUFFER, 0, 0, size)
    GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, 0)
    GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, 0)
