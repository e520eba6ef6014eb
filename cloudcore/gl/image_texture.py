"""A texture holding an RGBA8 numpy image, for the editor to show a picture made on the CPU (the heat map).

Rows are uploaded top row first, so the GUI draws the texture with v running
down (unlike the GL-rendered frames, which it flips).  Needs the window's GL
context current; `close` frees the texture.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL


class ImageTexture:
    def __init__(self):
        self.texture = GL.glGenTextures(1)
        self.shape: tuple[int, int] | None = None  # (height, width) of the storage allocated
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        # one texel per pixel at the viewport's size: nearest keeps the counts' edges honest
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)

    def upload(self, rgba: np.ndarray) -> int:
        """Replace the texture's contents with `rgba` (height, width, 4) uint8; returns the texture id."""
        if rgba.dtype != np.uint8 or rgba.ndim != 3 or rgba.shape[2] != 4:
            raise ValueError(f"expected an RGBA8 image (height, width, 4) uint8, got {rgba.dtype} {rgba.shape}")
        height, width = rgba.shape[:2]
        pixels = np.ascontiguousarray(rgba)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        if self.shape != (height, width):
            GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGBA8, width, height, 0, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE, pixels)
            self.shape = (height, width)
        else:
            GL.glTexSubImage2D(GL.GL_TEXTURE_2D, 0, 0, 0, width, height, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE, pixels)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        return self.texture

    def close(self) -> None:
        GL.glDeleteTextures([self.texture])
