"""The project's one import of pyrender, and the list of pyrender's private parts we rely on.

pyrender comes from `pyrender-maintained` (PyPI), a fork of pyrender 0.1.45 that
keeps the `pyrender` import name and the renderer unchanged (renderer.py is
byte-for-byte 0.1.45's) and fixes what stopped it working on current Pythons:
`np.infty`, which numpy 2 removed (mmatl/pyrender#288), the `six` metaclasses,
and the 3x3 uniform matrix setter.  Its PyOpenGL requirement is open
(>= 3.1.0), so we can require 3.1.9 or later, which works on Python 3.12 and
3.13 where 0.1.45's exact pin of 3.1.0 fails.  Everything else in
`cloudcore.gl` takes pyrender from this module.

We reach past pyrender's public API in four places, named in `PRIVATE_API`;
tests/project/test_pyrender_compat.py fails if an upgrade removes any of them.

Set PYOPENGL_PLATFORM=egl in the environment before this import for headless
rendering: PyOpenGL chooses its platform on first import.
"""

import pyrender

#: (class, attribute, why we need it); instance attributes are checked on a live renderer
PRIVATE_API = (
    (
        "Renderer",
        "_configure_forward_pass_viewport",
        "our renderer overrides it to draw the world into our framebuffer (gl/context.py)",
    ),
    ("OffscreenRenderer", "_platform", "its EGL context, made current before our own GL calls"),
    ("EGLPlatform", "_egl_display", "closing one headless context must not terminate the display (gl/context.py)"),
    ("EGLPlatform", "_egl_context", "the context destroyed alone while other headless contexts are open"),
)

__all__ = ["PRIVATE_API", "pyrender"]
