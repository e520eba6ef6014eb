"""The GL state every cloud draw shares: premultiplied blending over the frame, depth tested, never written."""

from __future__ import annotations

from contextlib import contextmanager

from OpenGL import GL


@contextmanager
def cloud_blending(depth_test: bool, counting: bool):
    """Blend ONE, ONE_MINUS_SRC_ALPHA (premultiplied colour), or ONE, ONE when counting fragments.

    Clouds are translucent: they test against the world's depth but do not
    write it, so everything behind them stays visible through them.
    """
    (GL.glEnable if depth_test else GL.glDisable)(GL.GL_DEPTH_TEST)
    GL.glDepthFunc(GL.GL_LESS)
    GL.glDepthMask(GL.GL_FALSE)
    GL.glDisable(GL.GL_CULL_FACE)
    GL.glEnable(GL.GL_BLEND)
    GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE if counting else GL.GL_ONE_MINUS_SRC_ALPHA)
    try:
        yield
    finally:
        GL.glDisable(GL.GL_BLEND)
        GL.glDepthMask(GL.GL_TRUE)
