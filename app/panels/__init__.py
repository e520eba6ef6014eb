"""The editor's panels, one module each: each reads and edits the `Editor` and calls the engine; no rendering
maths here."""

from __future__ import annotations

from app.editor import Editor
from app.panels.build import BuildPanel
from app.panels.camera import CameraPanel
from app.panels.cloud_field import CloudFieldPanel
from app.panels.clouds import CloudsPanel
from app.panels.lighting import LightingPanel
from app.panels.lod import LodPanel
from app.panels.scene import ScenePanel
from app.panels.statistics import StatisticsPanel
from app.panels.widgets import ReleasedSliders
from app.viewport import Viewport


class Panels:
    """Every panel of the editor, and the dockable windows they are drawn in."""

    def __init__(self, editor: Editor, viewport: Viewport):
        sliders = ReleasedSliders()
        self.scene = ScenePanel(editor)
        self.clouds = CloudsPanel(editor, sliders)
        self.build = BuildPanel(editor)
        self.lighting = LightingPanel(editor, sliders)
        self.cloud_field = CloudFieldPanel(editor, viewport, sliders)
        self.lod = LodPanel(editor, viewport)
        self.camera = CameraPanel(editor, viewport)
        self.statistics = StatisticsPanel(editor, viewport)

    def windows(self) -> list[tuple[str, str, object]]:
        """(title, dock space, draw) of each panel's window."""
        return [
            ("Scene", "Left", self.scene.draw),
            ("Clouds", "Left", self.clouds.draw),
            ("Build", "Left", self.build.draw),
            ("Lighting", "Left", self.lighting.draw),
            ("Cloud field", "Left", self.cloud_field.draw),
            ("LOD", "Left", self.lod.draw),
            ("Camera", "Left", self.camera.draw),
            ("Statistics", "LeftBottom", self.statistics.draw),
        ]

    def poll_recording(self) -> None:
        self.camera.poll_recording()

    def close(self) -> None:
        self.camera.close()
