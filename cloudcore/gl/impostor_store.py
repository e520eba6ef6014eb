"""The GL side of impostors: renders what the frame plan says to regenerate and keeps the textures.

A unit's impostor (one cloud, or a group of interpenetrating clouds sorted
together: `cloudcore.lod.units`) is rendered from the eye recorded in the
plan's impostor cache, through the tight frustum of
`cloudcore.lod.impostors.impostor_view`, into a cell of the impostor atlas
(`cloudcore.gl.impostor_atlas`: a run of them is then one draw); ring segments
from their generation's eye (`cloudcore.lod.ring`) into textures of their own
from one `TexturePool`, few and wide.  The cells of units and the textures of
ring generations the plan no longer holds are given back.  A unit split
around objects has one image per layer, each holding the particles of its
depth range seen from the impostor's eye.  The CPU's way (`splat_order`)
sorts each image's particles in numpy; the GPU's chooses and sorts all of an
atlas's images in one selection of cells and draws them in one indirect
multi-draw a 16 (`SplatPass.draw_cells`), the CPU's work independent of
their particles.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from OpenGL import GL

from cloudcore.gl.impostor_atlas import AtlasImage, ImpostorAtlas
from cloudcore.gl.splats import SplatPass
from cloudcore.gl.targets import TextureTarget
from cloudcore.gl.texture_pool import TexturePool
from cloudcore.lod.atlas import power_of_two_at_least
from cloudcore.lod.impostors import ImpostorView, cropped_corners, impostor_view, particle_extent
from cloudcore.lod.plan import FramePlan
from cloudcore.lod.ring import RingGeneration, panel_corners, segment_camera
from cloudcore.lod.splitting import layer_bounds
from cloudcore.model.settings import RenderSettings
from cloudcore.particles.batch import SplatSelection, splat_batch
from cloudcore.particles.buffer import ParticleBuffer

#: the atlas layers' side: the default largest impostor, one layer 2 MiB; larger impostors get an atlas of their side
ATLAS_LAYER_SIDE = 512


class ImpostorStore:
    def __init__(self, splats: SplatPass):
        self._splats = splats
        #: Wang's ring's segments, each with its clouds' nearest depth (`ring_panel`)
        self.pool = TexturePool(own_depth=True)
        self._atlases: dict[int, ImpostorAtlas] = {}  # layer side -> atlas
        #: unit members -> (images of its layers far to near, the view they were made with, the part of
        #: the images its particles can cover: only that part of the quad is drawn, the unit's mean blend
        #: weight they were made at: a cloud field's fade scales them from there)
        self._clouds: dict[tuple, tuple[list[AtlasImage], ImpostorView, tuple, float]] = {}
        self._ring: dict[tuple[RingGeneration, int], tuple[TextureTarget, tuple]] = {}  # (texture, extent)

    def update(
        self,
        plan: FramePlan,
        particles: ParticleBuffer,
        settings: RenderSettings,
        time_s: float,
        splat_order: str,
        unit_weights: Callable[[list], np.ndarray],
    ) -> int:
        """Render this frame's regenerations and ring segment at scene time `time_s`, the regenerations' particles
        chosen and sorted the way `splat_order` says ("cpu" or "gpu": `_cells_on_gpu`); `unit_weights` gives the
        mean blend weights of a list of units' members, held with their images.  Returns the particles rendered,
        but not those the GPU chose (`SplatPass.take_selected` counts those)."""
        units = plan.units
        # (atlas image, batch, view, projection, cleared first): all sorted, then all shaded (the ring's with
        # them), then drawn
        renders = []
        on_gpu = []  # (atlas image, eye, clouds, their depth ranges, view, projection): the GPU's way
        regenerated = sorted(plan.clouds.regenerate)
        made_at = unit_weights([plan.clouds[index].members for index in regenerated])
        for index, weight in zip(regenerated, made_at):
            cloud = plan.clouds[index]
            record = plan.records[cloud.members]
            view = impostor_view(units.centres[cloud.index], units.radii[cloud.index], record.eye)
            targets = self._cloud_images(cloud.members, cloud.texture_size, len(record.splits) + 1)
            self._clouds[cloud.members] = (
                targets,
                view,
                _extent(particles, cloud.members, view.view, view.projection, (cloud.texture_size,) * 2),
                float(weight),
            )
            for layer, target in enumerate(targets):
                depth_ranges = (layer_bounds(record.splits, layer),) * len(cloud.members)
                if splat_order == "gpu":
                    on_gpu.append((target, record.eye, cloud.members, depth_ranges, view.view, view.projection))
                    continue
                batch = splat_batch(particles, cloud.members, record.eye, depth_ranges, time_s)
                renders.append((target, batch, view.view, view.projection, True))
        for index in set(self._clouds) - set(plan.records):
            self._release(self._clouds.pop(index)[0])

        ring = plan.ring
        ring_renders = []  # (segment's target, batch, view, projection, cleared first): its colour, then its depth
        for segment, piece, members in ring.segment_builds() if ring is not None else ():
            if not members:
                continue
            # a piece of the segment, its clouds far to near (`cloudcore.lod.ring`): the first clears the texture,
            # the next are drawn over it
            generation, first = ring.building, piece[0] == 0
            size = generation.texture_size
            view, projection = segment_camera(generation, segment, settings.ring_elevation_deg)
            # the clouds as they were when the ring was planned: moved back by the wind's drift since
            back = np.eye(4)
            back[:3, 3] = -plan.ring_build_shift
            view = view @ back
            clouds = [cloud for unit in members for cloud in unit]
            extent = _extent(particles, clouds, view, projection, size)
            if first:
                target = self.pool.acquire(*size)
            else:
                target, held = self._ring[generation, segment]
                extent = _union(held, extent)
            self._ring[generation, segment] = (target, extent)
            # seen through the air from the ring's eye, each cloud at its own distance (the panel, drawn without
            # it, stands at the ring radius while its clouds reach the horizon: docs/lod.md, "Wang's ring")
            ring_eye = np.add(generation.eye, plan.ring_build_shift)
            batch = splat_batch(particles, clouds, ring_eye, None, time_s, through_air=True)
            ring_renders.append((target, batch, view, projection, first))
        selections = _cell_selections(particles, time_s, on_gpu)
        self._splats.shade_ahead(
            [(batch, view) for _, batch, view, _, _ in renders + ring_renders]
            + [(selection, views) for selection, views, _ in selections]
        )
        self._draw_cells([render[:4] for render in renders], settings)
        for selection, views, images in selections:
            self._draw_cells_on_gpu(selection, views, images)
        for target, batch, view, projection, cleared in ring_renders:
            # the clouds alone, no depth test: the texture holds their premultiplied colour and opacity
            target.bind_cleared() if cleared else target.bind()
            self._splats.draw(batch, view, projection, depth_test=False, point_sprites=settings.point_sprites)
            # the nearest of its clouds' particles drawn, each texel's: where the panel stands in depth (the
            # terrain between the ring's radius and a cloud hides it: `ring_panel`), over their whole discs (their
            # cores left the fringes at the panel's depth, a bright rim over the hills that hid the rest); the
            # pieces after the first keep the nearer of theirs and what is there
            target.clear_depth() if cleared else target.bind()
            GL.glColorMask(GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE)  # the depth pass writes no colour
            self._splats.draw_nearest_depth(
                particles, time_s, batch.order, batch.eye, view, projection, target.height, core=1.0
            )
            GL.glColorMask(GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE)
            GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDisable(GL.GL_SCISSOR_TEST)  # the last atlas cell's: it would clip the cloud pass
        for side in [side for side, atlas in self._atlases.items() if not atlas.in_use]:
            self._atlases.pop(side).close()
        live = {plan.ring_state.current, plan.ring_state.pending}
        for key in [key for key in self._ring if key[0] not in live]:
            self.pool.release(self._ring.pop(key)[0])
        return sum(len(batch) for _, batch, _, _, _ in renders)

    def _draw_cells(self, renders, settings: RenderSettings) -> None:
        """Render (atlas image, batch, view, projection) into their cells, cleared first: per atlas, those all of
        point sprites in one multi-draw (`SplatPass.draw_point_cells`: with the one shading dispatch, a third of a
        regeneration's fixed cost on llvmpipe: docs/performance.md, "A frame's regenerations together"), the others
        one by one."""
        by_atlas: dict[int, list] = {}
        for render in renders:
            by_atlas.setdefault(id(render[0].atlas), []).append(render)
        for group in by_atlas.values():
            atlas, as_points, alone = group[0][0].atlas, [], []
            for image, batch, view, projection in group:
                image.bind_cleared()  # a cleared bound target: glClearTexSubImage cost llvmpipe more a regeneration
                points = (
                    self._splats.as_points_in(batch, view, projection, image.viewport)
                    if settings.point_sprites
                    else None
                )
                if points is None:
                    alone.append((image, batch, view, projection))
                else:
                    as_points.append((batch, view, *points, image.viewport, image.cell.layer))
            if as_points:
                atlas.bind_layers()
                self._splats.draw_point_cells(as_points)
            for image, batch, view, projection in alone:
                image.bind()
                self._splats.draw(batch, view, projection, depth_test=False, point_sprites=settings.point_sprites)

    def _draw_cells_on_gpu(self, selection: SplatSelection, views: np.ndarray, cells) -> None:
        """Render a selection of cells (`_cell_selections`): cleared one by one, then drawn in one multi-draw a
        MAX_VIEWPORTS of them (`SplatPass.draw_cells`)."""
        for image, _ in cells:
            image.bind_cleared()
        cells[0][0].atlas.bind_layers()
        self._splats.draw_cells(
            selection, views, [(projection, image.viewport, image.cell.layer) for image, projection in cells]
        )

    @property
    def texture_bytes(self) -> int:
        """GPU memory of the atlases and of the ring's textures, in use and idle."""
        return self.pool.bytes_total + sum(atlas.nbytes for atlas in self._atlases.values())

    def cloud_impostor(self, members: tuple, layer: int = 0) -> tuple[AtlasImage, np.ndarray, np.ndarray, float]:
        """(image of layer `layer` of the unit of clouds `members`, the world corners of the part of its
        quad that can show particles, the part of the image they cover (u0, v0, u1, v1), the unit's mean
        blend weight it was made at)."""
        images, corners, extents, made_at = self.cloud_impostors([(members, layer)])
        return images[0], corners[0], extents[0], float(made_at[0])

    def cloud_impostors(self, keys) -> tuple[list[AtlasImage], np.ndarray, np.ndarray, np.ndarray]:
        """`cloud_impostor` of each (members, layer) of `keys`, the corners (n, 4, 3), parts (n, 4) and weights
        (n,) as arrays."""
        held = [(self._clouds[members], layer) for members, layer in keys]
        corners = np.array([view.corners for (_, view, _, _), _ in held], dtype=np.float64).reshape(-1, 4, 3)
        extents = np.array([extent for (_, _, extent, _), _ in held], dtype=np.float64).reshape(-1, 4)
        made_at = np.array([weight for (*_, weight), _ in held], dtype=np.float64)
        images = [targets[layer] for (targets, *_), layer in held]
        return images, cropped_corners(corners, extents), extents, made_at

    def ring_panel(
        self, generation: RingGeneration, segment: int, elevation_deg: float
    ) -> tuple[TextureTarget, np.ndarray, tuple]:
        """(texture, cropped world corners, extent) of a ring segment's panel, as `cloud_impostor`; the texture's
        `depth_texture` holds, per texel, the depth of its nearest particle seen from the ring's eye through the
        segment's camera (`segment_camera`), 1 where none."""
        target, extent = self._ring[generation, segment]
        return target, cropped_corners(panel_corners(generation, segment, elevation_deg), extent), extent

    def _cloud_images(self, members: tuple, size: int, layers: int) -> list[AtlasImage]:
        """`layers` atlas images of side `size`, reusing the unit's cells where they are of the size it needs."""
        held = self._clouds.pop(members, ([], None))[0]
        atlas = self._atlas_for(size)
        cell_side = atlas.layout.cell_side(size)
        kept = [image for image in held if image.atlas is atlas and image.cell.side == cell_side][:layers]
        self._release([image for image in held if image not in kept])
        kept = [AtlasImage(atlas, image.cell, size) for image in kept]
        return kept + [atlas.allocate(size) for _ in range(layers - len(kept))]

    def _atlas_for(self, size: int) -> ImpostorAtlas:
        side = power_of_two_at_least(size, ATLAS_LAYER_SIDE)
        if side not in self._atlases:
            self._atlases[side] = ImpostorAtlas(side)
        return self._atlases[side]

    @staticmethod
    def _release(images) -> None:
        for image in images:
            image.atlas.release(image)

    def close(self) -> None:
        for target, _ in self._ring.values():
            target.close()
        for atlas in self._atlases.values():
            atlas.close()
        self._clouds.clear()
        self._ring.clear()
        self._atlases.clear()
        self.pool.close()


def _cell_selections(particles: ParticleBuffer, time_s: float, cells) -> list[tuple]:
    """The GPU's way for a frame's regenerations `cells` (atlas image, eye, clouds, their depth ranges, view,
    projection): per atlas and eye, one selection of them all, each image a cell; as (selection, the cells'
    views, (image, projection) per cell).  A frame remakes its impostors from its own eye, so one selection
    an atlas serves them all."""
    groups: dict[tuple, list] = {}
    for cell in cells:
        groups.setdefault((id(cell[0].atlas), tuple(cell[1])), []).append(cell)
    selections = []
    for group in groups.values():
        clouds = tuple(cloud for _, _, members, *_ in group for cloud in members)
        depth_ranges = tuple(depth for _, _, _, ranges, *_ in group for depth in ranges)
        indices = tuple(index for index, (_, _, members, *_) in enumerate(group) for _ in members)
        eye = np.asarray(group[0][1], dtype=np.float64)
        selection = SplatSelection(particles, clouds, eye, depth_ranges, time_s, None, indices)
        views = np.array([view for *_, view, _ in group], dtype=np.float64)
        selections.append((selection, views, [(image, projection) for image, *_, projection in group]))
    return selections


def _union(extent: tuple, other: tuple) -> tuple:
    """The part of a texture two extents (u0, v0, u1, v1) cover together (an empty one, u1 <= u0, covers none)."""
    if other[2] <= other[0]:
        return extent
    if extent[2] <= extent[0]:
        return other
    return (min(extent[0], other[0]), min(extent[1], other[1]), max(extent[2], other[2]), max(extent[3], other[3]))


def _extent(particles: ParticleBuffer, clouds, view, projection, size) -> tuple:
    """The part of a texture rendered through (view, projection) that the particles of `clouds` can cover."""
    starts = particles.cloud_starts
    pieces = [slice(starts[c], starts[c + 1]) for c in clouds]  # a cloud's particles are contiguous
    if not pieces:
        return particle_extent(view, projection, np.zeros((0, 3)), np.zeros(0), size)
    centres = np.concatenate([particles.centres[piece] for piece in pieces])
    return particle_extent(view, projection, centres, np.concatenate([particles.radii[p] for p in pieces]), size)
