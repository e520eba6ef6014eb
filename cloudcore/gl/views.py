"""Rendering scenes' named views for screenshot tests: one headless context per frame size, reused for every view."""

from __future__ import annotations

import numpy as np

from cloudcore.gl.frame import FrameRenderer
from cloudcore.lod.costs import LLVMPIPE_COSTS
from cloudcore.lod.plan import LodState
from cloudcore.measure.screenshot_check import view_camera, view_settings
from cloudcore.model.scene import Scene, View


class ViewRenderer:
    """Renders views headlessly; a context is made for the first view of each size (making one is slow) and
    kept until close().

    Every view is rendered as the first frame of its own: the level of detail starts from nothing and auto
    mode prices its choices with the pinned llvmpipe cost model, never with timings of earlier frames, so a
    view gives the same pixels whichever views were rendered before it, on the same machine.
    """

    def __init__(self):
        self._renderers: dict[tuple[int, int], FrameRenderer] = {}

    def render(self, scene: Scene, view: View, size: tuple[int, int]) -> np.ndarray:
        """The view as sRGB uint8 (height, width, 3)."""
        if size not in self._renderers:
            self._renderers[size] = FrameRenderer(*size)
        renderer = self._renderers[size]
        renderer.lod_state = LodState()
        image, _ = renderer.render(
            scene,
            time_of_day=view.time_of_day,
            camera=view_camera(scene, view),
            settings=view_settings(view),
            time_s=view.time_s,
            costs=LLVMPIPE_COSTS,
        )
        return image

    def close(self) -> None:
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers.clear()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
