"""The headless OpenGL context (pyrender's EGL OffscreenRenderer) and our render targets.

pyrender owns the context; we borrow it for raw GL.  Its `render()` leaves the
context un-current when it returns, so every raw-GL entry point here calls
`make_current()` first.

The frame is composed in linear light in an RGBA16F colour buffer with a 24-bit
depth buffer.  pyrender's output (8 bits per channel) is copied beside it with
glBlitFramebuffer: its depth straight into our depth buffer (the formats must
match, hence DEPTH_COMPONENT24), its colour into `world_texture` for the world
pass to decode and composite over the sky.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.pyrender_compat import pyrender


class HeadlessContext:
    """An EGL context of a fixed size with a linear-colour + depth target and pyrender's colour."""

    def __init__(self, width: int, height: int):
        if width < 1 or height < 1:
            raise ValueError(f"framebuffer size must be positive, got {width}x{height}")
        self.width, self.height = int(width), int(height)
        self.renderer = pyrender.OffscreenRenderer(self.width, self.height)
        self.make_current()
        self._colour, self.depth_renderbuffer = GL.glGenRenderbuffers(2)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self._colour)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_RGBA16F, self.width, self.height)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self.depth_renderbuffer)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, self.width, self.height)
        self.framebuffer = _framebuffer(colour_renderbuffer=self._colour, depth_renderbuffer=self.depth_renderbuffer)

        self.world_texture = GL.glGenTextures(1)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.world_texture)
        GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, GL.GL_RGBA8, self.width, self.height)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        self._world_framebuffer = _framebuffer(colour_texture=self.world_texture)

    def make_current(self) -> None:
        self.renderer._platform.make_current()

    def bind_target(self) -> None:
        """Make the context current and direct drawing into the linear render target."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.framebuffer)
        GL.glViewport(0, 0, self.width, self.height)

    def render_pyrender_scene(self, scene, flags) -> None:
        """Render a pyrender scene: its depth into the target's depth, its colour into `world_texture`.

        `OffscreenRenderer.render` always reads its result back to numpy; we copy
        from the resolved framebuffer it leaves behind (pyrender 0.1.45 keeps it
        in `Renderer._main_fb`), so colour and depth stay on the GPU.
        """
        self.renderer.render(scene, flags=flags)
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.renderer._renderer._main_fb)
        w, h = self.width, self.height
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self.framebuffer)
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self._world_framebuffer)
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_COLOR_BUFFER_BIT, GL.GL_NEAREST)
        self.bind_target()

    def clear_world(self) -> None:
        """The state `render_pyrender_scene` leaves for an empty scene: nothing in colour or depth."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._world_framebuffer)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        self.bind_target()
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearDepth(1.0)
        GL.glClear(GL.GL_DEPTH_BUFFER_BIT)

    def read_linear_rgb(self) -> np.ndarray:
        """The render target as float32 (height, width, 3), top row first."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.framebuffer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, GL.GL_RGB, GL.GL_FLOAT)
        pixels = np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, 3)
        return pixels[::-1].copy()

    def close(self) -> None:
        """Free the GL objects and the EGL context; the object is unusable afterwards."""
        if self.renderer is None:
            return
        self.make_current()
        GL.glDeleteFramebuffers(2, [self.framebuffer, self._world_framebuffer])
        GL.glDeleteRenderbuffers(2, [self._colour, self.depth_renderbuffer])
        GL.glDeleteTextures([self.world_texture])
        self.renderer.delete()
        self.renderer = None


def _framebuffer(*, colour_renderbuffer=None, depth_renderbuffer=None, colour_texture=None) -> int:
    framebuffer = GL.glGenFramebuffers(1)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
    if colour_renderbuffer is not None:
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER,
                                     colour_renderbuffer)
    if colour_texture is not None:
        GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, colour_texture, 0)
    if depth_renderbuffer is not None:
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER,
                                     depth_renderbuffer)
    status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
    if status != GL.GL_FRAMEBUFFER_COMPLETE:
        raise RuntimeError(f"framebuffer incomplete (status 0x{int(status):x})")
    return framebuffer
