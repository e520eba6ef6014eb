"""Offscreen render targets: a colour texture, optionally sharing a depth renderbuffer.

Used for the overdraw counter (R32F, sharing the frame's depth so hidden
fragments are not counted), impostor textures, screen layers and the reduced
cloud pass (RGBA16F, premultiplied linear colour; the last over a depth texture,
with an R8 map of the screen's tiles it covers: `cloudcore.gl.reduced_clouds`)
and the editor's display image (RGBA8, sRGB).
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

#: bytes per texel of the formats used here, for texture-memory statistics
_TEXEL_BYTES = {GL.GL_RGBA16F: 8, GL.GL_R32F: 4, GL.GL_RGBA8: 4, GL.GL_R8: 1, GL.GL_DEPTH_COMPONENT32F: 4}
_READ_FORMAT = {
    GL.GL_RGBA16F: (GL.GL_RGBA, 4),
    GL.GL_R32F: (GL.GL_RED, 1),
    GL.GL_RGBA8: (GL.GL_RGBA, 4),
    GL.GL_R8: (GL.GL_RED, 1),
}


def linear_filtering(target: int, wrap: int = GL.GL_CLAMP_TO_EDGE) -> None:
    """The bound texture of `target` sampled linearly, wrapping by `wrap` on each of its axes."""
    GL.glTexParameteri(target, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(target, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    axes = (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T) + (
        (GL.GL_TEXTURE_WRAP_R,) if target == GL.GL_TEXTURE_3D else ()
    )
    for axis in axes:
        GL.glTexParameteri(target, axis, wrap)


class TextureTarget:
    """A framebuffer whose colour attachment is a linear-filtered texture of `internal_format`."""

    def __init__(
        self,
        width: int,
        height: int,
        internal_format=GL.GL_RGBA16F,
        depth_renderbuffer: int | None = None,
        depth_texture: int | None = None,
        own_depth: bool = False,
    ):
        """With `depth_renderbuffer` or `depth_texture` (one of the two), drawn depth-tested against it; with
        `own_depth`, a depth texture of its own (`depth_texture`, read by nearest texel: Wang's ring's segments
        hold their clouds' nearest depth beside their colour)."""
        self.width, self.height, self.internal_format = int(width), int(height), internal_format
        self.depth_texture = None
        if own_depth:
            self.depth_texture = depth_texture = GL.glGenTextures(1)
            GL.glBindTexture(GL.GL_TEXTURE_2D, depth_texture)
            GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_DEPTH_COMPONENT32F, self.width, self.height)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        self.texture = GL.glGenTextures(1)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, internal_format, self.width, self.height)
        linear_filtering(GL.GL_TEXTURE_2D)
        self.framebuffer = GL.glGenFramebuffers(1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.framebuffer)
        GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, self.texture, 0)
        if depth_renderbuffer is not None:
            GL.glFramebufferRenderbuffer(
                GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER, depth_renderbuffer
            )
        elif depth_texture is not None:
            GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_TEXTURE_2D, depth_texture, 0)
        status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            raise RuntimeError(f"framebuffer incomplete (status 0x{int(status):x})")

    @property
    def nbytes(self) -> int:
        depth = _TEXEL_BYTES[GL.GL_DEPTH_COMPONENT32F] if self.depth_texture is not None else 0
        return self.width * self.height * (_TEXEL_BYTES[self.internal_format] + depth)

    def bind(self) -> None:
        """Draw into this target from now on, over what it holds."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.framebuffer)
        GL.glViewport(0, 0, self.width, self.height)
        GL.glDisable(GL.GL_SCISSOR_TEST)  # an atlas cell's, or the GUI's, would clip it

    def bind_cleared(self) -> None:
        """Draw into this target from now on, starting from transparent black (depth untouched)."""
        self.bind()
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)

    def clear_depth(self) -> None:
        """Draw into this target from now on, its depth back at the far plane (colour untouched)."""
        self.bind()
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearDepth(1.0)
        GL.glClear(GL.GL_DEPTH_BUFFER_BIT)

    def read(self) -> np.ndarray:
        """The texture as float32 (height, width[, channels]), top row first."""
        layout, channels = _READ_FORMAT[self.internal_format]
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.framebuffer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, layout, GL.GL_FLOAT)
        pixels = np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, channels)
        return (pixels[::-1, :, 0] if channels == 1 else pixels[::-1]).copy()

    def close(self) -> None:
        GL.glDeleteFramebuffers(1, [self.framebuffer])
        GL.glDeleteTextures([self.texture] + ([self.depth_texture] if self.depth_texture is not None else []))


def depth_renderbuffer(width: int, height: int) -> int:
    """A 24-bit depth renderbuffer, the format pyrender's depth is blitted from."""
    renderbuffer = GL.glGenRenderbuffers(1)
    GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, renderbuffer)
    GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, width, height)
    return renderbuffer


def blit_depth(source_framebuffer: int, source_size, target_framebuffer: int, target_size) -> None:
    """Copy (and rescale, nearest texel) the depth of one framebuffer into another."""
    GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, source_framebuffer)
    GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, target_framebuffer)
    GL.glBlitFramebuffer(0, 0, *source_size, 0, 0, *target_size, GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)


class DepthTexture:
    """A depth texture and a framebuffer drawing into it alone, remade when the size asked for changes: a copy of
    another framebuffer's depth (a renderbuffer, which a shader cannot read), or a depth drawn for a shader to
    read."""

    def __init__(self):
        self.texture, self._framebuffer, self._size = None, None, None

    def copy(self, framebuffer: int, size: tuple[int, int]) -> int:
        """The texture, filled with the depth of `framebuffer` (of `size`); leaves it bound for drawing."""
        self._make(size)
        blit_depth(framebuffer, size, self._framebuffer, size)
        return self.texture

    def bind_cleared(self, size: tuple[int, int]) -> None:
        """Draw into the texture of `size` from now on, depth tested and written, starting from the far plane."""
        self._make(size)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._framebuffer)
        GL.glViewport(0, 0, *size)
        GL.glDisable(GL.GL_SCISSOR_TEST)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearDepth(1.0)
        GL.glClear(GL.GL_DEPTH_BUFFER_BIT)

    def read(self) -> np.ndarray:
        """The window depths (height, width) float32, top row first (tests)."""
        width, height = self._size
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        data = GL.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        return np.frombuffer(data, dtype=np.float32).reshape(height, width)[::-1].copy()

    def _make(self, size: tuple[int, int]) -> None:
        if self._size == size:
            return
        self.close()
        self.texture = GL.glGenTextures(1)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_DEPTH_COMPONENT24, *size)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        self._framebuffer = GL.glGenFramebuffers(1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._framebuffer)
        GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_TEXTURE_2D, self.texture, 0)
        GL.glDrawBuffer(GL.GL_NONE)
        GL.glReadBuffer(GL.GL_NONE)
        self._size = size

    def close(self) -> None:
        if self.texture is not None:
            GL.glDeleteTextures([self.texture])
            GL.glDeleteFramebuffers(1, [self._framebuffer])
        self.texture, self._framebuffer, self._size = None, None, None
