"""The GL side of impostors: renders what the frame plan says to regenerate and keeps the textures.

Per-cloud impostors are rendered from the eye recorded in the plan's impostor
cache, through the tight frustum of `cloudcore.impostors.impostor_view`; ring
segments from their generation's eye (`cloudcore.ring`).  Textures come from
one `TexturePool`; those of clouds or ring generations the plan no longer
holds go back to it.  A cloud split around objects has one texture per
layer, each holding the particles of its depth range seen from the
impostor's eye.
"""

from __future__ import annotations

import math

from cloudcore.eye_scattering import ParticleShading
from cloudcore.frameplan import FramePlan
from cloudcore.gl.splats import SplatPass, splat_batch
from cloudcore.gl.targets import TextureTarget
from cloudcore.gl.texture_pool import TexturePool
from cloudcore.impostors import ImpostorView, impostor_view, required_size
from cloudcore.ring import SEGMENT_DEG, RingGeneration, segment_camera
from cloudcore.settings import RenderSettings
from cloudcore.splitting import layer_bounds


class ImpostorStore:
    def __init__(self, splats: SplatPass):
        self._splats = splats
        self.pool = TexturePool()
        self._clouds: dict[int, tuple[list[TextureTarget], ImpostorView]] = {}  # layers far to near
        self._ring: dict[tuple[RingGeneration, int], TextureTarget] = {}
        self._ring_sizes: dict[RingGeneration, tuple[int, int]] = {}

    def update(self, plan: FramePlan, particles: ParticleShading, viewport, fov_y_deg: float,
               settings: RenderSettings, time_s: float) -> int:
        """Render this frame's regenerations and ring segment at scene time `time_s`; returns the particles rendered."""
        rendered = 0
        for cloud in plan.clouds:
            if cloud.regenerate is None:
                continue
            record = plan.records[cloud.index]
            view = impostor_view(particles.bounding_centres[cloud.index], particles.bounding_radii[cloud.index],
                                 record.eye)
            targets = self._cloud_targets(cloud.index, cloud.texture_size, len(record.splits) + 1)
            self._clouds[cloud.index] = (targets, view)
            for layer, target in enumerate(targets):
                depth_range = layer_bounds(record.splits, layer)
                rendered += self._render(target, particles, [cloud.index], record.eye, view.view, view.projection,
                                         time_s, [depth_range])
        for index in set(self._clouds) - set(plan.records):
            self._release(self._clouds.pop(index)[0])

        ring = plan.ring
        if ring is not None and ring.build_segment in (ring.state.pending.occupied_segments if ring.state.pending else ()):
            generation, segment = ring.state.pending, ring.build_segment
            size = self._ring_sizes.setdefault(generation, _ring_texture_size(viewport, fov_y_deg, settings))
            target = self._ring[generation, segment] = self.pool.acquire(*size)
            view, projection = segment_camera(generation, segment, settings.ring_elevation_deg)
            rendered += self._render(target, particles, generation.segment_members[segment], generation.eye,
                                     view, projection, time_s)
        live = {plan.ring_state.current, plan.ring_state.pending}
        for key in [key for key in self._ring if key[0] not in live]:
            self.pool.release(self._ring.pop(key))
        for generation in set(self._ring_sizes) - live:
            del self._ring_sizes[generation]
        return rendered

    def cloud_impostor(self, index: int, layer: int = 0) -> tuple[TextureTarget, ImpostorView]:
        targets, view = self._clouds[index]
        return targets[layer], view

    def ring_panel(self, generation: RingGeneration, segment: int) -> TextureTarget:
        return self._ring[generation, segment]

    def _cloud_targets(self, index: int, size: int, layers: int) -> list[TextureTarget]:
        """`layers` textures of side `size`, reusing the cloud's where they fit."""
        held = self._clouds.pop(index, ([], None))[0]
        kept = [target for target in held if target.width == size][:layers]
        self._release([target for target in held if target not in kept])
        return kept + [self.pool.acquire(size, size) for _ in range(layers - len(kept))]

    def _release(self, targets) -> None:
        for target in targets:
            self.pool.release(target)

    def _render(self, target: TextureTarget, particles, clouds, eye, view, projection, time_s: float,
                depth_ranges=None) -> int:
        """The clouds alone, no depth test: the texture holds their premultiplied colour and opacity."""
        batch = splat_batch(particles, clouds, eye, depth_ranges, time_s)
        target.bind_cleared()
        self._splats.draw(batch, view, projection, depth_test=False)
        return len(batch)

    def close(self) -> None:
        for targets, _ in self._clouds.values():
            for target in targets:
                target.close()
        for target in self._ring.values():
            target.close()
        self._clouds.clear()
        self._ring.clear()
        self.pool.close()


def _ring_texture_size(viewport, fov_y_deg: float, settings: RenderSettings) -> tuple[int, int]:
    """(width, height) of a ring segment texture: the screen's pixel density over 45 x 2 elevation degrees."""
    pixels_per_tangent = viewport[1] / (2.0 * math.tan(math.radians(fov_y_deg) / 2.0))
    width = 2.0 * math.tan(math.radians(SEGMENT_DEG / 2.0)) * pixels_per_tangent
    height = 2.0 * math.tan(math.radians(settings.ring_elevation_deg)) * pixels_per_tangent
    return (required_size(width, settings.impostor_min_size, settings.impostor_max_size),
            required_size(height, settings.impostor_min_size, settings.impostor_max_size))
