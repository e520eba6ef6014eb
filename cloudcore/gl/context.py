"""Where frames are drawn: our render targets inside either a headless EGL context or the GUI's window.

The frame is composed in linear light in an RGBA16F colour texture with a
24-bit depth buffer (`RenderTargets`).  pyrender draws the world's colour
(8 bits, sRGB-encoded) into `world_texture` and its depth into that same depth
buffer, which the cloud passes then test against.  How pyrender gets there
differs:

- `HeadlessContext` (tools, tests): pyrender's EGL `OffscreenRenderer` owns
  the context and renders into its own framebuffer; we blit colour and depth
  across (the depth formats must match, hence DEPTH_COMPONENT24).  Its
  `render()` leaves the context un-current, so every raw-GL entry point calls
  `make_current()` first.
- `WindowContext` (the editor): the window's context is current already; a
  `pyrender.Renderer` draws straight into our world framebuffer.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.pyrender_compat import pyrender


def check_frame_size(width: int, height: int) -> None:
    """Refuse a frame without pixels (a minimised window asks for 0x0)."""
    if width < 1 or height < 1:
        raise ValueError(f"framebuffer size must be positive, got {width}x{height}")


class RenderTargets:
    """The linear colour + depth target of one frame size and the world's colour beside it."""

    def __init__(self, width: int, height: int):
        check_frame_size(width, height)
        self.width, self.height = int(width), int(height)
        self.depth_renderbuffer = GL.glGenRenderbuffers(1)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self.depth_renderbuffer)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, self.width, self.height)
        self.colour_texture = _texture(self.width, self.height, GL.GL_RGBA16F)
        self.framebuffer = _framebuffer(self.colour_texture, self.depth_renderbuffer)
        self.world_texture = _texture(self.width, self.height, GL.GL_RGBA8)
        self.world_framebuffer = _framebuffer(self.world_texture, self.depth_renderbuffer)

    def make_current(self) -> None:
        """Make the GL context current (a no-op where the owner keeps it current)."""

    def bind_target(self) -> None:
        """Make the context current and direct drawing into the linear render target."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.framebuffer)
        GL.glViewport(0, 0, self.width, self.height)

    def clear_world(self) -> None:
        """The state pyrender leaves for an empty scene: nothing in the world colour, far depth."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.world_framebuffer)
        GL.glViewport(0, 0, self.width, self.height)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClearDepth(1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        self.bind_target()

    def read_linear_rgb(self) -> np.ndarray:
        """The render target as float32 (height, width, 3), top row first."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.framebuffer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, GL.GL_RGB, GL.GL_FLOAT)
        pixels = np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, 3)
        return pixels[::-1].copy()

    def read_depth(self) -> np.ndarray:
        """The target's depth as float32 (height, width) window depths in [0, 1], top row first."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.framebuffer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
        return np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width)[::-1].copy()

    def close_targets(self) -> None:
        GL.glDeleteFramebuffers(2, [self.framebuffer, self.world_framebuffer])
        GL.glDeleteRenderbuffers(1, [self.depth_renderbuffer])
        GL.glDeleteTextures([self.colour_texture, self.world_texture])


class HeadlessContext(RenderTargets):
    """An EGL context of a fixed size (PYOPENGL_PLATFORM=egl) with our targets."""

    #: headless contexts open in this process; they share its one EGL display (`close`)
    open_count = 0

    def __init__(self, width: int, height: int):
        check_frame_size(width, height)
        self.renderer = pyrender.OffscreenRenderer(int(width), int(height))
        HeadlessContext.open_count += 1
        self.make_current()
        super().__init__(width, height)

    def make_current(self) -> None:
        self.renderer._platform.make_current()

    def render_pyrender_scene(self, scene, flags, framebuffer: int | None = None) -> None:
        """Render a pyrender scene: its depth into the target's depth, its colour into `world_texture`.

        Or both into `framebuffer` (colour RGBA8, depth DEPTH_COMPONENT24), the objects' target.
        `OffscreenRenderer.render` always reads its result back to numpy; we copy
        from the resolved framebuffer it leaves behind (pyrender 0.1.45 keeps it
        in `Renderer._main_fb`), so colour and depth stay on the GPU.
        """
        self.renderer.render(scene, flags=flags)
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.renderer._renderer._main_fb)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self.world_framebuffer if framebuffer is None else framebuffer)
        w, h = self.width, self.height
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)
        self.bind_target()

    @property
    def closed(self) -> bool:
        return self.renderer is None

    def close(self) -> None:
        """Free the GL objects and the EGL context; the object is unusable afterwards."""
        if self.renderer is None:
            return
        self.make_current()
        self.close_targets()
        HeadlessContext.open_count -= 1
        if HeadlessContext.open_count:
            _destroy_only_the_context(self.renderer._platform)
        self.renderer.delete()
        self.renderer = None


def _destroy_only_the_context(platform) -> None:
    """Make pyrender's `delete_context` destroy the EGL context alone.

    pyrender deletes a context with eglTerminate of its display too, and EGL has one display per device
    for the whole process, not counted: that would kill every other headless context still open (the
    next call on one fails with EGL_BAD_DISPLAY).  The last one to close terminates it as pyrender does.
    """
    from OpenGL.EGL import EGL_NO_CONTEXT, EGL_NO_SURFACE, eglDestroyContext, eglMakeCurrent

    def delete_context() -> None:
        eglMakeCurrent(platform._egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT)
        eglDestroyContext(platform._egl_display, platform._egl_context)
        platform._egl_context = platform._egl_display = None

    platform.delete_context = delete_context


class _RendererIntoFramebuffer(pyrender.Renderer):
    """pyrender's on-screen renderer, pointed at a framebuffer of ours instead of the window's."""

    target_framebuffer = 0

    def _configure_forward_pass_viewport(self, flags):
        super()._configure_forward_pass_viewport(flags)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self.target_framebuffer)


class WindowContext(RenderTargets):
    """Our targets inside a context someone else made current (the editor's window)."""

    def __init__(self, width: int, height: int):
        super().__init__(width, height)
        self._renderer = _RendererIntoFramebuffer(self.width, self.height)

    def render_pyrender_scene(self, scene, flags, framebuffer: int | None = None) -> None:
        self._renderer.target_framebuffer = self.world_framebuffer if framebuffer is None else framebuffer
        self._renderer.render(scene, flags)
        self.bind_target()

    @property
    def closed(self) -> bool:
        return self._renderer is None

    def close(self) -> None:
        if self._renderer is None:
            return
        self.close_targets()
        self._renderer.delete()
        self._renderer = None


def _texture(width: int, height: int, internal_format) -> int:
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexStorage2D(GL.GL_TEXTURE_2D, 1, internal_format, width, height)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
    return texture


def _framebuffer(colour_texture: int, depth_renderbuffer: int) -> int:
    framebuffer = GL.glGenFramebuffers(1)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, colour_texture, 0)
    GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER, depth_renderbuffer)
    status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
    if status != GL.GL_FRAMEBUFFER_COMPLETE:
        raise RuntimeError(f"framebuffer incomplete (status 0x{int(status):x})")
    return framebuffer
