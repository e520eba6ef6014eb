"""Headless OpenGL rendering of cloudview scenes: the only package that imports OpenGL or pyrender.

Set PYOPENGL_PLATFORM=egl before importing this package to render without a
display (PyOpenGL picks its platform on first import).

    from cloudcore.gl import render_full
    rgb, stats = render_full(load_scene("cloudcore/resources/scenes/valley.toml"), 640, 480)
"""

from cloudcore.gl.frame import FrameRenderer, render_full

__all__ = ["FrameRenderer", "render_full"]
