"""The project's one import of pyrender, made to work under numpy 2.

pyrender 0.1.45 (pinned; its last release) still uses `np.infty`, which numpy 2
removed, so `Mesh.bounds` and `Scene.bounds` raise AttributeError without the
alias (upstream mmatl/pyrender#288, fixes unmerged).  Aliasing here, before the
import, keeps numpy 2 for the rest of the project.  Everything else in
`cloudcore.gl` takes pyrender from this module.

Set PYOPENGL_PLATFORM=egl in the environment before this import for headless
rendering: PyOpenGL chooses its platform on first import.
"""

import numpy as np

if not hasattr(np, "infty"):
    np.infty = np.inf

import pyrender  # noqa: E402  (needs the alias above)

__all__ = ["pyrender"]
