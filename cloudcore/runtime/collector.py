"""Python's cyclic garbage collector, kept off the frame: what is set up once is left out of its full passes.

A full collection walks every object the collector tracks, and once a scene
is loaded and drawn there are about 134,000 (numpy, PyOpenGL, pyrender,
trimesh, the scene's records): 62 to 77 ms a pass on the 2-core llvmpipe
machine, inside whichever frame's allocations set it off. The 1.2M-particle
field's planning allocates enough to set one off every 15 frames (4.6 ms a
frame on the mean, a 70 ms stall each time); in a side-by-side benchmark it
fell on whichever mode was running. `gc.freeze` moves the objects alive at
that moment to a permanent generation, which full passes skip (0.5 ms a pass
after it); objects made later are collected as before. What is frozen and
later dropped is still freed by reference counting; only cycles among it stay.
"""

from __future__ import annotations

import gc


def freeze_what_is_set_up() -> None:
    """Collect once, then leave every object alive now out of later collections (after the first frames:
    the scene loaded, the shaders compiled, the caches made)."""
    gc.collect()
    gc.freeze()
