"""An object inside a split cloud, drawn between the cloud's layers."""

from __future__ import annotations

from cloudcore.gl.draw.executor import CloudPassFrame, DrawCounts, DrawExecutor, DrawStep, draw_kind


@draw_kind("object")
class ObjectBetweenLayers(DrawExecutor):
    """The object over the layers behind it, without writing depth (the layers before it blend over it); at a
    reduced cloud resolution the clouds behind it are laid over the screen first, at its resolution."""

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        if frame.reduced is not None:
            frame.reduced.composite(frame.context)
        frame.objects.draw(
            frame.context,
            frame.camera,
            frame.poses,
            [step.items[0].index],
            write_depth=False,
            antialiased=frame.settings.world_antialiasing,
            air=None if frame.air is None else frame.air[0],
            shadows=frame.shadows,
        )
        if frame.reduced is not None:
            frame.reduced.resume()
        return DrawCounts()
