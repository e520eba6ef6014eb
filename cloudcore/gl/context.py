"""Where frames are drawn: our render targets inside either a headless EGL context or the GUI's window.

The frame is composed in linear light in an RGBA16F colour texture with a
24-bit depth buffer (`RenderTargets`).  The world pass draws the terrain and the
sky into it (`cloudcore.gl.world`), and the terrain's depth, which the cloud
passes then test against.  In both contexts a `pyrender.Renderer` draws the
objects straight into a framebuffer of ours, so the editor and the headless
tools make the same picture:

- `HeadlessContext` (tools, tests): pyrender's EGL `OffscreenRenderer` owns
  the context (we never call its `render`, which draws with 4x multisampling
  and reads the result back to numpy every frame).  Every raw-GL entry point
  calls `make_current()` first.
- `WindowContext` (the editor): the window's context is current already.

Multisampling the world is a choice per frame (`multisampled_target`, and
`render_pyrender_scene`'s `antialiased`): on llvmpipe it doubles the world pass
for a picture hardly different (docs/performance.md, "The world pass: where its time goes"), so the frame's
default is without.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.pyrender_compat import pyrender

#: samples of an antialiased world: what pyrender's own offscreen renderer used, and what every GL 3.0+ must offer
WORLD_SAMPLES = 4


def check_frame_size(width: int, height: int) -> None:
    """Refuse a frame without pixels (a minimised window asks for 0x0)."""
    if width < 1 or height < 1:
        raise ValueError(f"framebuffer size must be positive, got {width}x{height}")


class RenderTargets:
    """The linear colour + depth target of one frame size."""

    def __init__(self, width: int, height: int):
        check_frame_size(width, height)
        self.width, self.height = int(width), int(height)
        self.depth_renderbuffer = GL.glGenRenderbuffers(1)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self.depth_renderbuffer)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, self.width, self.height)
        self.colour_texture = _texture(self.width, self.height, GL.GL_RGBA16F)
        self.framebuffer = _framebuffer(self.colour_texture, self.depth_renderbuffer)
        # the objects' scene's renderer, its own: a renderer frees the meshes of every scene but the one it
        # draws (`Renderer._update_context`)
        self._pyrender = _RendererIntoFramebuffer(self.width, self.height)
        #: (framebuffer, colour and depth renderbuffers) with 4 samples, 8-bit for pyrender's objects and linear
        #: for the world, each made by the first antialiased draw that needs it
        self._multisampled: dict[int, tuple[int, list[int]]] = {}

    def make_current(self) -> None:
        """Make the GL context current (a no-op where the owner keeps it current)."""

    def bind_target(self) -> None:
        """Make the context current and direct drawing into the linear render target."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.framebuffer)
        GL.glViewport(0, 0, self.width, self.height)

    def render_pyrender_scene(self, scene, flags, framebuffer: int, *, antialiased: bool = False):
        """Render a pyrender scene into `framebuffer` (colour RGBA8, depth DEPTH_COMPONENT24), the objects'
        target.  With `antialiased`, into a 4x multisampled framebuffer first, resolved into the destination
        (the depth takes one sample per pixel, as a resolve of depth does).
        """
        self.make_current()
        drawn_into = self._multisampled_framebuffer(GL.GL_RGBA8) if antialiased else framebuffer
        self._pyrender.target_framebuffer = drawn_into
        self._pyrender.render(scene, flags)
        if antialiased:
            self._resolve(drawn_into, framebuffer)
        self.bind_target()

    def multisampled_target(self) -> int:
        """A 4x multisampled framebuffer of the target's formats (linear RGBA16F, depth), for the world."""
        self.make_current()
        return self._multisampled_framebuffer(GL.GL_RGBA16F)

    def resolve_multisampled_target(self) -> None:
        """Resolve `multisampled_target` into the render target: colour averaged, depth one sample a pixel."""
        self._resolve(self._multisampled_framebuffer(GL.GL_RGBA16F), self.framebuffer)

    def _resolve(self, multisampled: int, destination: int) -> None:
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, multisampled)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, destination)
        w, h = self.width, self.height
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT, GL.GL_NEAREST)

    def _multisampled_framebuffer(self, colour_format: int) -> int:
        if colour_format not in self._multisampled:
            renderbuffers = [int(r) for r in GL.glGenRenderbuffers(2)]
            for renderbuffer, internal_format in zip(renderbuffers, (colour_format, GL.GL_DEPTH_COMPONENT24)):
                GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, renderbuffer)
                GL.glRenderbufferStorageMultisample(
                    GL.GL_RENDERBUFFER, WORLD_SAMPLES, internal_format, self.width, self.height
                )
            framebuffer = GL.glGenFramebuffers(1)
            GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
            for attachment, renderbuffer in zip((GL.GL_COLOR_ATTACHMENT0, GL.GL_DEPTH_ATTACHMENT), renderbuffers):
                GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, attachment, GL.GL_RENDERBUFFER, renderbuffer)
            _check_complete("multisampled")
            self._multisampled[colour_format] = (framebuffer, renderbuffers)
        return self._multisampled[colour_format][0]

    def read_linear_rgb(self) -> np.ndarray:
        """The render target as float32 (height, width, 3), top row first: a read-only view of the pixels read
        (a copy of a 4096x4096 frame is 200 MB more)."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.framebuffer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, GL.GL_RGB, GL.GL_FLOAT)
        return np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, 3)[::-1]

    def read_depth(self) -> np.ndarray:
        """The target's depth as float32 (height, width) window depths in [0, 1], top row first."""
        self.make_current()
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.framebuffer)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
        return np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width)[::-1].copy()

    def close_targets(self) -> None:
        self._pyrender.delete()
        GL.glDeleteFramebuffers(1, [self.framebuffer])
        GL.glDeleteRenderbuffers(1, [self.depth_renderbuffer])
        GL.glDeleteTextures([self.colour_texture])
        for framebuffer, renderbuffers in self._multisampled.values():
            GL.glDeleteFramebuffers(1, [framebuffer])
            GL.glDeleteRenderbuffers(len(renderbuffers), renderbuffers)
        self._multisampled = {}


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

    @property
    def closed(self) -> bool:
        return self._pyrender is None

    def close(self) -> None:
        if self._pyrender is None:
            return
        self.close_targets()
        self._pyrender = None


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
    _check_complete("render target")
    return framebuffer


def _check_complete(what: str) -> None:
    status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
    if status != GL.GL_FRAMEBUFFER_COMPLETE:
        raise RuntimeError(f"{what} framebuffer incomplete (status 0x{int(status):x})")


#: EGL_NV_device_cuda's attribute: the CUDA device an EGL device is
EGL_CUDA_DEVICE_NV = 0x323A


def egl_device_of_cuda(cuda_device: int) -> int | None:
    """The index among EGL's devices (what pyrender's `EGL_DEVICE_ID` counts) of CUDA device `cuda_device`: Ray
    names a task's GPUs as CUDA devices, and EGL need not list them in CUDA's order.  None where no device says
    which it is (Mesa's, or a driver without EGL_NV_device_cuda): the default device is then used."""
    import ctypes

    from OpenGL import EGL

    def extension(name: str, result, *arguments):
        address = EGL.eglGetProcAddress(name)
        return ctypes.CFUNCTYPE(result, *arguments)(address) if address else None

    count = ctypes.c_int(0)
    query_devices = extension(
        "eglQueryDevicesEXT", ctypes.c_uint, ctypes.c_int, ctypes.POINTER(ctypes.c_void_p), ctypes.POINTER(ctypes.c_int)
    )
    query_attribute = extension(
        "eglQueryDeviceAttribEXT", ctypes.c_uint, ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_ssize_t)
    )
    if query_devices is None or query_attribute is None or not query_devices(0, None, ctypes.byref(count)):
        return None
    devices = (ctypes.c_void_p * max(count.value, 1))()
    if not query_devices(count.value, devices, ctypes.byref(count)):
        return None
    for index in range(count.value):
        value = ctypes.c_ssize_t(-1)
        if query_attribute(devices[index], EGL_CUDA_DEVICE_NV, ctypes.byref(value)) and value.value == cuda_device:
            return index
    return None
