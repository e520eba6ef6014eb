"""The GL side of impostors: renders what the frame plan says to regenerate and keeps the textures.

A unit's impostor (one cloud, or a group of interpenetrating clouds sorted
together: `cloudcore.lod.units`) is rendered from the eye recorded in the
plan's impostor cache, through the tight frustum of
`cloudcore.lod.impostors.impostor_view`; ring segments from their generation's
eye (`cloudcore.lod.ring`).  Textures come from one `TexturePool`; those of units
or ring generations the plan no longer holds go back to it.  A unit split
around objects has one texture per layer, each holding the particles of its
depth range seen from the impostor's eye.
"""

from __future__ import annotations

import numpy as np

from cloudcore.gl.splats import SplatPass, splat_batch
from cloudcore.gl.targets import TextureTarget
from cloudcore.gl.texture_pool import TexturePool
from cloudcore.light.eye_scattering import ParticleBuffer
from cloudcore.lod.frameplan import FramePlan
from cloudcore.lod.impostors import ImpostorView, cropped_corners, impostor_view, particle_extent
from cloudcore.lod.ring import RingGeneration, panel_corners, segment_camera
from cloudcore.lod.splitting import layer_bounds
from cloudcore.settings import RenderSettings


class ImpostorStore:
    def __init__(self, splats: SplatPass):
        self._splats = splats
        self.pool = TexturePool()
        #: unit members -> (textures of its layers far to near, the view they were made with, the part of
        #: the textures its particles can cover: only that part of the quad is drawn)
        self._clouds: dict[tuple, tuple[list[TextureTarget], ImpostorView, tuple]] = {}
        self._ring: dict[tuple[RingGeneration, int], tuple[TextureTarget, tuple]] = {}  # (texture, extent)

    def update(self, plan: FramePlan, particles: ParticleBuffer, settings: RenderSettings, time_s: float) -> int:
        """Render this frame's regenerations and ring segment at scene time `time_s`; returns the particles rendered."""
        units = plan.units
        renders = []  # (target, batch, view, projection): all sorted, then all shaded, then drawn
        for cloud in plan.clouds:
            if cloud.regenerate is None:
                continue
            record = plan.records[cloud.members]
            view = impostor_view(units.centres[cloud.index], units.radii[cloud.index], record.eye)
            targets = self._cloud_targets(cloud.members, cloud.texture_size, len(record.splits) + 1)
            self._clouds[cloud.members] = (
                targets,
                view,
                _extent(particles, cloud.members, view.view, view.projection, (cloud.texture_size,) * 2),
            )
            for layer, target in enumerate(targets):
                depth_ranges = [layer_bounds(record.splits, layer)] * len(cloud.members)
                batch = splat_batch(particles, cloud.members, record.eye, depth_ranges, time_s)
                renders.append((target, batch, view.view, view.projection))
        for index in set(self._clouds) - set(plan.records):
            self._release(self._clouds.pop(index)[0])

        ring = plan.ring
        if ring is not None and ring.build_segment in (
            ring.state.pending.occupied_segments if ring.state.pending else ()
        ):
            generation, segment = ring.state.pending, ring.build_segment
            size = generation.texture_size
            target = self.pool.acquire(*size)
            view, projection = segment_camera(generation, segment, settings.ring_elevation_deg)
            clouds = [cloud for unit in generation.segment_members[segment] for cloud in unit]
            self._ring[generation, segment] = (target, _extent(particles, clouds, view, projection, size))
            renders.append((target, splat_batch(particles, clouds, generation.eye, None, time_s), view, projection))
        self._splats.shade_ahead([(batch, view) for _, batch, view, _ in renders])
        for target, batch, view, projection in renders:
            # the clouds alone, no depth test: the texture holds their premultiplied colour and opacity
            target.bind_cleared()
            self._splats.draw(batch, view, projection, depth_test=False, point_sprites=settings.point_sprites)
        live = {plan.ring_state.current, plan.ring_state.pending}
        for key in [key for key in self._ring if key[0] not in live]:
            self.pool.release(self._ring.pop(key)[0])
        return sum(len(batch) for _, batch, _, _ in renders)

    def cloud_impostor(self, members: tuple, layer: int = 0) -> tuple[TextureTarget, np.ndarray, tuple]:
        """(texture of layer `layer` of the unit of clouds `members`, the world corners of the part of its
        quad that can show particles, the part of the texture they cover (u0, v0, u1, v1))."""
        targets, view, extent = self._clouds[members]
        return targets[layer], cropped_corners(view.corners, extent), extent

    def ring_panel(
        self, generation: RingGeneration, segment: int, elevation_deg: float
    ) -> tuple[TextureTarget, np.ndarray, tuple]:
        """(texture, cropped world corners, extent) of a ring segment's panel, as `cloud_impostor`."""
        target, extent = self._ring[generation, segment]
        return target, cropped_corners(panel_corners(generation, segment, elevation_deg), extent), extent

    def _cloud_targets(self, members: tuple, size: int, layers: int) -> list[TextureTarget]:
        """`layers` textures of side `size`, reusing the unit's where they fit."""
        held = self._clouds.pop(members, ([], None))[0]
        kept = [target for target in held if target.width == size][:layers]
        self._release([target for target in held if target not in kept])
        return kept + [self.pool.acquire(size, size) for _ in range(layers - len(kept))]

    def _release(self, targets) -> None:
        for target in targets:
            self.pool.release(target)

    def close(self) -> None:
        for targets, _, _ in self._clouds.values():
            for target in targets:
                target.close()
        for target, _ in self._ring.values():
            target.close()
        self._clouds.clear()
        self._ring.clear()
        self.pool.close()


def _extent(particles: ParticleBuffer, clouds, view, projection, size) -> tuple:
    """The part of a texture rendered through (view, projection) that the particles of `clouds` can cover."""
    starts = particles.cloud_starts
    pieces = [slice(starts[c], starts[c + 1]) for c in clouds]  # a cloud's particles are contiguous
    if not pieces:
        return particle_extent(view, projection, np.zeros((0, 3)), np.zeros(0), size)
    centres = np.concatenate([particles.centres[piece] for piece in pieces])
    return particle_extent(view, projection, centres, np.concatenate([particles.radii[p] for p in pieces]), size)
