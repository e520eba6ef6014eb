"""Full 3D: a run of consecutive full-3D layers as one sorted splat batch (they interpenetrate), blended as
billboards by the raster, composited by the tiled compute pass, or composited as volumes (Yusov 5.5)."""

from __future__ import annotations

import numpy as np

from cloudcore.gl.draw.executor import CloudPassFrame, DrawCounts, DrawExecutor, DrawStep, PassTools, draw_kind
from cloudcore.light.volume_blending import blending_path
from cloudcore.particles.batch import SplatBatch, SplatSelection


@draw_kind("full")
class Full3D(DrawExecutor):
    """A run of full-3D layers: chosen and sorted on the GPU when that is the frame's way and they are blended
    as billboards (volume blending reads its batch on the CPU), else on the CPU."""

    def batch(self, frame: CloudPassFrame, step: DrawStep) -> SplatBatch | SplatSelection:
        if frame.splat_order == "gpu" and frame.settings.blending == "plain":
            clouds, depth_ranges = frame.members_and_ranges(step.items)
            return SplatSelection(
                frame.particles, clouds, frame.eye, depth_ranges, frame.time_s, frame.frustum, through_air=True
            )
        return frame.batch_of(step.items)

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        return draw_splats(self.tools, frame, step.batch)

    def count_fragments(self, frame: CloudPassFrame, step: DrawStep) -> tuple:
        count_splats(self.tools, frame, step.batch)
        return (step.batch,)


def draw_splats(
    tools: PassTools, frame: CloudPassFrame, batch: SplatBatch | SplatSelection, colour_texture: int | None = None
) -> DrawCounts:
    """Full 3D: a batch of splats on the pass's target (or the screen layer whose `colour_texture` is bound), as
    billboards or as volumes; the particles drawn, but none for a selection: the GPU counts those
    (`SplatPass.take_selected`)."""
    splats, volume = tools.splats, tools.volume
    view, projection = frame.view, frame.projection
    if isinstance(batch, SplatSelection):
        composited = False
        compositable = volume.features.compute_shaders and splats.plain_selection(batch)
        if frame.compositing == "compute" and compositable:
            instances, count_at = splats.selected_instances(batch, view)
            target, framebuffer, size = _drawn_into(frame, colour_texture)
            composited = volume.draw(
                instances, view, projection, target, framebuffer, size, plain=True, count_at=count_at
            )
        if composited:
            splats.count_drawn(batch)
        else:  # not asked for, not plain splats, or too many pairs to bin
            splats.draw(batch, view, projection)
        return DrawCounts(compositable=batch.slots if compositable else 0)
    path = blending_path(
        frame.settings.blending,
        compute_shaders=volume.features.compute_shaders,
        plain_splats_only=bool(np.all(splats.plain_splats(batch))),
    )
    composited = False
    if path == "volume" and len(batch):
        buffer, first = splats.shade(batch, view)
        target, framebuffer, size = _drawn_into(frame, colour_texture)
        composited = volume.draw((buffer, first, len(batch)), view, projection, target, framebuffer, size)
    if not composited:  # plain billboards, asked for or past the binning's pairs
        splats.draw(batch, view, projection, point_sprites=frame.settings.point_sprites)
    return DrawCounts(particles=len(batch), as_volumes=len(batch) if composited else 0)


def count_splats(tools: PassTools, frame: CloudPassFrame, batch: SplatBatch | SplatSelection) -> None:
    """`draw_splats`'s fragments, counted: as billboards, whichever way they were composited."""
    tools.splats.draw(batch, frame.view, frame.projection, counting=True, point_sprites=frame.settings.point_sprites)


def _drawn_into(frame: CloudPassFrame, colour_texture: int | None) -> tuple[int, int, tuple[int, int]]:
    """(the colour texture, the framebuffer whose depth cuts it, their size) a compositing pass draws into: the
    frame's target or the reduced pass's, or `colour_texture` (a screen layer of the same size and depth)."""
    if frame.reduced is None:
        framebuffer, size, texture = frame.context.framebuffer, frame.size, frame.context.colour_texture
    else:
        target = frame.reduced.target
        framebuffer, size, texture = target.framebuffer, frame.reduced.size, target.texture
    return (texture if colour_texture is None else colour_texture), framebuffer, size
