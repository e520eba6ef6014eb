"""Quads from the impostor store: units' impostors, units crossfading between their impostor and full 3D, and
Wang's ring's panels."""

from __future__ import annotations

import itertools

import numpy as np

from cloudcore.gl.draw.executor import CloudPassFrame, DrawCounts, DrawExecutor, DrawStep, draw_kind
from cloudcore.gl.draw.full_3d import count_splats, draw_splats
from cloudcore.gl.impostor_atlas import atlas_instances
from cloudcore.gl.targets import TextureTarget
from cloudcore.lod.ring import MIN_PANEL_DISTANCE, segment_camera
from cloudcore.particles.batch import SplatBatch


@draw_kind("impostor")
class Impostors(DrawExecutor):
    """Units' impostors (a layer each, when split around objects), consecutive in the pass: one instanced draw
    from the atlas (two, where larger impostors than its layers' side need one of their own), their state set
    once for the run."""

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        for atlas_texture, instances in self._atlas_runs(frame, step):
            self.tools.quads.draw_instanced(
                instances, frame.view_projection, atlas_texture, air=frame.air, shafts=frame.shafts
            )
        return DrawCounts()

    def count_fragments(self, frame: CloudPassFrame, step: DrawStep) -> tuple:
        for atlas_texture, instances in self._atlas_runs(frame, step):
            self.tools.quads.draw_instanced(instances, frame.view_projection, atlas_texture, counting=True)
        return ()

    def _atlas_runs(self, frame: CloudPassFrame, step: DrawStep) -> list[tuple[int, np.ndarray]]:
        """(atlas texture, its quads' instances) per run of the step's impostors in one atlas."""
        items = step.items
        clouds = [frame.plan.clouds[item.index] for item in items]
        images, corners, extents, made_at = self.tools.impostors.cloud_impostors(
            [(cloud.members, item.layer) for cloud, item in zip(clouds, items)]
        )
        corners = corners + frame.plan.impostor_shifts([item.index for item in items])[:, None, :]
        faded = frame.faded([cloud.members for cloud in clouds], made_at)
        weights = np.array([cloud.impostor_weight for cloud in clouds]) * faded
        runs = []
        for _, run in itertools.groupby(range(len(images)), key=lambda i: id(images[i].atlas)):  # one atlas a run
            run = list(run)
            instances = atlas_instances([images[i] for i in run], corners[run], weights[run], extents[run])
            runs.append((images[run[0]].atlas.texture, instances))
        return runs


@draw_kind("crossfade")
class Crossfade(DrawExecutor):
    """A unit between its impostor and full 3D: its splats into a screen layer, mixed with the impostor."""

    def __init__(self, tools):
        super().__init__(tools)
        self._layer: TextureTarget | None = None  # screen-sized, sharing the frame's depth

    def batch(self, frame: CloudPassFrame, step: DrawStep) -> SplatBatch:
        return frame.batch_of(step.items)

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        atlas_texture, instance = self._impostor(frame, step)
        layer = self._screen_layer(frame) if frame.reduced is None else frame.reduced.layer()
        layer.bind_cleared()
        drawn = draw_splats(self.tools, frame, step.batch, layer.texture)
        frame.bind_cloud_target()
        full_weight = frame.plan.clouds[step.items[0].index].full_weight
        self.tools.quads.draw_instanced(
            instance,
            frame.view_projection,
            atlas_texture,
            air=frame.air,
            shafts=frame.shafts,
            layer_texture=layer.texture,
            layer_weight=full_weight,
        )
        return drawn

    def count_fragments(self, frame: CloudPassFrame, step: DrawStep) -> tuple:
        count_splats(self.tools, frame, step.batch)
        atlas_texture, instance = self._impostor(frame, step)
        self.tools.quads.draw_instanced(instance, frame.view_projection, atlas_texture, counting=True)
        return (step.batch,)

    def _impostor(self, frame: CloudPassFrame, step: DrawStep) -> tuple[int, np.ndarray]:
        """(atlas texture, the instance of the unit's impostor quad), faded as its unit."""
        item = step.items[0]
        cloud = frame.plan.clouds[item.index]
        image, corners, extent, made_at = self.tools.impostors.cloud_impostor(cloud.members, item.layer)
        corners = corners + frame.plan.impostor_shifts([item.index])[0]
        faded = frame.faded([cloud.members], np.array([made_at]))
        return image.atlas.texture, atlas_instances([image], corners[None], cloud.impostor_weight * faded, extent[None])

    def _screen_layer(self, frame: CloudPassFrame) -> TextureTarget:
        if self._layer is None:
            self._layer = TextureTarget(*frame.size, depth_renderbuffer=frame.context.depth_renderbuffer)
        return self._layer

    def close_screen_targets(self) -> None:
        if self._layer is not None:
            self._layer.close()
            self._layer = None

    @property
    def texture_bytes(self) -> int:
        return self._layer.nbytes if self._layer is not None else 0


@draw_kind("ring")
class Ring(DrawExecutor):
    """Wang's ring: the panels of the generations drawn (two while a rebuilt one fades in), world-space quads
    one after the other, before the plan's draw items."""

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        # not through the air: their segments hold their clouds through it, from the ring's eye; each fragment at
        # its clouds' depth, not the panel's
        elevation_deg = frame.settings.ring_elevation_deg
        panels = [
            (
                corners,
                target.texture,
                target.depth_texture,
                weight,
                extent,
                np.add(generation.eye, shift),
                max(generation.radius, MIN_PANEL_DISTANCE),
            )
            for generation, target, corners, weight, extent, shift in self._panels(frame)
        ]
        if panels:  # every segment's camera has the one projection: the band's height, 45 degrees wide
            _, segment_projection = segment_camera(frame.plan.ring.draws[0][0], 0, elevation_deg)
            self.tools.quads.draw_panels(panels, frame.view_projection, segment_projection)
        return DrawCounts()

    def count_fragments(self, frame: CloudPassFrame, step: DrawStep) -> tuple:
        quads = [
            (corners, target.texture, weight, extent) for _, target, corners, weight, extent, _ in self._panels(frame)
        ]
        self.tools.quads.draw_run(quads, frame.view_projection, counting=True)
        return ()

    def _panels(self, frame: CloudPassFrame) -> list[tuple]:
        """(generation, target, corners, weight, uv_rect, the wind's shift of its clouds) of every panel drawn."""
        panels = []
        shifts = frame.plan.ring_shifts or [np.zeros(3)] * len(frame.plan.ring.draws)
        for (generation, weight), shift in zip(frame.plan.ring.draws, shifts):
            for segment in generation.occupied_segments:
                target, corners, extent = self.tools.impostors.ring_panel(
                    generation, segment, frame.settings.ring_elevation_deg
                )
                corners = np.asarray(corners + shift, dtype=np.float32)
                panels.append((generation, target, corners, float(weight), extent, shift))
        return panels
