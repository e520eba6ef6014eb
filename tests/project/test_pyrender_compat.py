"""pyrender's private parts that cloudcore.gl depends on still exist in the pyrender installed.

pyrender comes from `pyrender-maintained`, a fork: an upgrade that renames what
we override or reach into must fail here, not as a black viewport.
"""

import inspect
from importlib import metadata

import numpy as np


def test_the_pinned_libraries_are_the_ones_installed():
    assert metadata.version("pyrender-maintained")
    major, minor, patch = (int(part) for part in metadata.version("PyOpenGL").split(".")[:3])
    assert (major, minor, patch) >= (3, 1, 9), "PyOpenGL before 3.1.9 fails on Python 3.12+"


def test_the_overridden_forward_pass_viewport_is_still_called_by_render():
    from cloudcore.gl.context import _RendererIntoFramebuffer
    from cloudcore.gl.pyrender_compat import pyrender

    method = pyrender.Renderer.__dict__.get("_configure_forward_pass_viewport")
    assert callable(method), "pyrender.Renderer._configure_forward_pass_viewport is gone"
    assert list(inspect.signature(method).parameters) == ["self", "flags"]
    # our override only works while the forward pass still goes through it
    assert "self._configure_forward_pass_viewport(flags)" in inspect.getsource(pyrender.Renderer._forward_pass)
    assert _RendererIntoFramebuffer._configure_forward_pass_viewport is not method


def test_every_private_attribute_exists_on_a_live_headless_renderer(renderer, small_scene):
    from cloudcore.gl.pyrender_compat import PRIVATE_API

    renderer.render(small_scene)  # with terrain: pyrender renders into our framebuffer
    offscreen = renderer.context.renderer
    objects = {
        "OffscreenRenderer": offscreen,
        "Renderer": renderer.context._pyrender,
        "EGLPlatform": offscreen._platform,
    }
    missing = [f"{kind}.{name} ({why})" for kind, name, why in PRIVATE_API if not hasattr(objects[kind], name)]
    assert not missing, f"pyrender no longer has: {missing}"


def test_closing_a_headless_renderer_leaves_the_others_rendering(renderer, small_scene):
    """pyrender terminates the process's one EGL display with each context it deletes; ours keep it while
    other headless contexts are open (`cloudview check` in-process, the pytest plugin beside a user's own)."""
    from cloudcore.gl import FrameRenderer

    before = renderer.render(small_scene)[0]
    with FrameRenderer(32, 24) as other:
        other.render(small_scene)
    assert np.array_equal(renderer.render(small_scene)[0], before)
