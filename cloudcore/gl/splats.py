"""Splats: particles as instanced camera-facing billboards, blended back to front.

`SplatPass` draws a `ParticleBuffer`'s particles in the order of a draw (`cloudcore.particles.batch`) from
the GPU, in four parts, one concern each: the particles' terms uploaded once (`cloudcore.gl.splat_residency`),
each particle of a draw coloured for its eye (Harris eq. 5) by a compute shader into the instances the splats
are drawn from (`cloudcore.gl.splat_shading`), for a `SplatSelection` the particles chosen and sorted on the
GPU too, counted into an indirect draw (`cloudcore.gl.splat_order`): the CPU's work for the draw no longer
grows with its particles; and here the raster: quads, or point sprites where the picture is the same
(`cloudcore.particles.point_sprites`).  One selection may hold many draws from one eye, each into its own
cell of a layered target (a frame's impostor regenerations): chosen in one dispatch, sorted by distance then
by cell in one sort, drawn by one indirect multi-draw a 16 cells.  With the depth test on, terrain hides
splats; splats never write depth.  Drawn with `counting=True`, every fragment adds 1 instead (overdraw).
"""

from __future__ import annotations

import ctypes
import itertools

import numpy as np
from OpenGL import GL

from cloudcore.artist.facing import FacingState
from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.blending import cloud_blending
from cloudcore.gl.programs import build_program, set_matrix_at, set_vec3_at, uniform_locations
from cloudcore.gl.splat_order import COMMAND_UINTS, GpuSplatOrder
from cloudcore.gl.splat_residency import PARTICLE_FLOATS, ResidentParticles
from cloudcore.gl.splat_shading import INSTANCES_BINDING, TERMS_BINDING, SplatShading
from cloudcore.gl.storage import bind_storage, store
from cloudcore.light.splat_look import MAX_OPACITY, SplatLook
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, SPLAT_SHARPNESS
from cloudcore.model.cloud_records import ATLAS_GRID
from cloudcore.particles.batch import SplatBatch, SplatSelection
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.particles.point_sprites import draw_runs, guard_band, point_sprite_mask
from cloudcore.world.camera import view_rotation

#: two triangles over a particle's four corners (lower left, lower right, upper left, upper right)
_QUAD_TRIANGLES = np.array([0, 1, 2, 2, 1, 3], dtype=np.uint32)
#: splat.vert.glsl's `Cell` (CELLS): view rotation, projection, viewport height and layer; its binding
_CELL_FLOATS = 36
_CELLS_BINDING = 8
#: the uniforms of a look other than plain (splat.frag.glsl's PIXEL_LOOK)
_LOOK_UNIFORMS = ("detail_amplitude", "detail_scale")
#: viewports (and scissors) a multi-draw of cells can address: what GL 4.1 guarantees, llvmpipe's and NVIDIA's
_MAX_VIEWPORTS = 16
#: a particle fainter than this (its opacity times its formation or blend weight) is left out of the clouds'
#: nearest depth (`draw_nearest_depth`): the light shafts' march ends its ray at a cloud that is seen
NEAREST_DEPTH_OPACITY = 0.01
#: of a particle's radius, the disc that cuts the march: out to its kernel's 1/e point (`SPLAT_SHARPNESS`).  A ray
#: cut at a cloud's thin fringe keeps from the sky behind the fringe the shafts behind the cloud: the whole disc
#: brightened the edges of a cumulonimbus seen from the side more than half of it
#: (docs/atmosphere.md#the-shafts-and-the-air-in-front-of-the-clouds)
NEAREST_DEPTH_CORE = 0.5


class SplatPass:
    """The splats' raster, over their residency, shading and the GPU's order (one of each, shared by its draws)."""

    def __init__(self):
        #: (points?, counting?, atlas sprites?, per pixel?, detail noise?) -> program, made when first drawn with (the
        #: plain look's at once); a point is never a sprite, and counting fragments has no look
        self._programs: dict[tuple, int] = {}
        #: per program, the locations of the uniforms every draw sets
        self._uniforms: dict[int, dict[str, int]] = {}
        for key in itertools.product((False, True), repeat=3):
            if not (key[0] and key[2]):
                self._program(*key, (False, False))
        self._point_sizes_px = tuple(float(size) for size in GL.glGetFloatv(GL.GL_POINT_SIZE_RANGE))
        self._resident = ResidentParticles()
        self._order = GpuSplatOrder(self._resident)
        self._shading = SplatShading(self._resident, self._order)
        #: particles drawn as point sprites since the frame's renderer last set it to 0 (for its statistics)
        self.particles_as_points = 0
        self._vertex_array = GL.glGenVertexArrays(1)
        #: the triangles of the particles' quads, the cells' table, the particles of the clouds' nearest depth
        self._corner_index_buffer, self._cell_buffer, self._depth_particle_buffer = self._buffers = GL.glGenBuffers(3)
        self._quads_indexed = 0
        #: the programs drawing many cells at once, made when first needed: (points?, atlas sprites?) -> (the
        #: program, its first cell's uniform); points never are sprites
        self._cell_programs: dict[tuple[bool, bool], tuple[int, int]] = {}
        #: the clouds' nearest depth's program and its uniforms (`draw_nearest_depth`), made when first needed
        self._depth_programs: dict[float, tuple[int, dict]] = {}  # by the share of a radius drawn (`CORE`)

    @property
    def shafts(self):
        """`SplatShading.shafts`: the frame's light shafts that the cloud pass's splats take off their air."""
        return self._shading.shafts

    @shafts.setter
    def shafts(self, shafts) -> None:
        self._shading.shafts = shafts

    @property
    def air(self) -> AirVolume | None:
        """The frame's air (`cloudcore.gl.air_volume`), uploaded for its eye, which batches `through_air` take;
        None: no air (the gradient sky)."""
        return self._shading.air

    @air.setter
    def air(self, air: AirVolume | None) -> None:
        self._shading.air = air

    @property
    def look(self) -> SplatLook:
        """How the splats are shaded per pixel (`cloudcore.light.splat_look`): every draw's, impostors' as the
        screen's, so that a cloud looks one way however it is drawn."""
        return self._shading.look

    @look.setter
    def look(self, look: SplatLook) -> None:
        self._shading.look = look

    def _look_variant(self, counting: bool) -> tuple[bool, bool]:
        """(per pixel?, detail noise?) of the programs drawing now: none when counting fragments."""
        look = self._shading.look
        return (False, False) if counting else (look.per_pixel, look.detail_noise > 0.0)

    def _program(self, points: bool, counting: bool, sprites: bool, look: tuple[bool, bool]) -> int:
        """The raster's program for a draw of points or quads, counting or blending, with atlas sprites or not, in
        the `look` variant (`_look_variant`); made on first use."""
        key = (points, counting, sprites, *look)
        if key not in self._programs:
            program = build_program(
                "splat", _splat_defines(points=points, sprites=sprites, look=look, counting=counting)
            )
            self._programs[key] = program
            self._uniforms[program] = uniform_locations(
                program,
                ("view_rotation", "projection", "viewport_height", *_LOOK_UNIFORMS),
            )
        return self._programs[key]

    def shade_ahead(self, batches_and_views) -> None:
        """`SplatShading.shade_ahead`: the (batch, view) pairs a pass will draw, shaded before any of its draws."""
        self._shading.shade_ahead(batches_and_views)

    def shade(self, batch: SplatBatch | SplatSelection, view: np.ndarray) -> tuple[int, int]:
        """`SplatShading.shade`: (the storage buffer holding the batch's instances for its eye, its first slot)."""
        return self._shading.shade(batch, view)

    def update_facing(self, particles: ParticleBuffer, start: int, state: FacingState) -> None:
        """The facing lock of particles `start`, `start + 1`, ... (one cloud's) for the next draws."""
        self._resident.update_facing(particles, start, state)

    def plain_splats(self, batch: SplatBatch) -> np.ndarray:
        """(n,) bool: which of the batch's particles are plain Gaussian splats of one colour
        (`cloudcore.particles.point_sprites.plain_splats`)."""
        return self._resident.plain_splats(batch)

    def plain_selection(self, selection: SplatSelection) -> bool:
        """Whether every particle of a selection's clouds is a plain Gaussian splat of one colour
        (`cloudcore.particles.point_sprites.plain_splats`) and the look is plain: what a compute pass can
        composite (it draws no pixel terms)."""
        return self.look.plain and self._resident.plain_selection(selection)

    def take_selected(self) -> tuple[int, int]:
        """`GpuSplatOrder.take_selected`: (the particles the selections drawn into targets since the last call
        chose, those drawn into cells)."""
        return self._order.take_selected()

    def draw(
        self,
        batch: SplatBatch,
        view: np.ndarray,
        projection: np.ndarray,
        *,
        depth_test: bool = True,
        counting: bool = False,
        point_sprites: bool = True,
    ) -> int:
        """Blend the batch over the bound target (premultiplied), or add 1 per fragment when counting.

        With `point_sprites`, the runs of the batch that `cloudcore.particles.point_sprites` allows are drawn as
        points, the rest as quads, in the batch's order; returns the particles drawn as points.
        A `SplatSelection` is drawn as quads, by one indirect draw.
        """
        if isinstance(batch, SplatSelection):
            return self._draw_selection(batch, view, projection, depth_test, counting)
        if not len(batch):
            return 0
        _, first = self._shading.shade(batch, view)
        rotation = view_rotation(view)
        target_viewport = GL.glGetIntegerv(GL.GL_VIEWPORT) if point_sprites else None
        pieces, projection, viewport = self._pieces(batch, rotation, projection, target_viewport)
        if viewport is not None:
            GL.glViewport(*viewport)
        with_sprites = self._resident.with_sprites(batch)
        look = self._look_variant(counting)
        programs = {
            points: self._program(points, counting, with_sprites and not points, look) for points in (False, True)
        }
        for as_points in {piece[2] for piece in pieces}:
            self._use(programs[as_points], rotation, projection, float(viewport[3]) if as_points else None)
        self._bind_quads(len(batch))
        GL.glEnable(GL.GL_PROGRAM_POINT_SIZE)
        with cloud_blending(depth_test, counting):
            for start, stop, as_points in pieces:
                GL.glUseProgram(programs[as_points])
                if as_points:
                    GL.glDrawArrays(GL.GL_POINTS, first + start, stop - start)
                else:
                    offset = ctypes.c_void_p(6 * 4 * start)  # six uint32 indices a particle, four vertices
                    GL.glDrawElementsBaseVertex(
                        GL.GL_TRIANGLES, 6 * (stop - start), GL.GL_UNSIGNED_INT, offset, 4 * first
                    )
        GL.glDisable(GL.GL_PROGRAM_POINT_SIZE)
        GL.glBindVertexArray(0)
        if viewport is not None:
            GL.glViewport(*target_viewport)
        as_points = sum(stop - start for start, stop, as_points in pieces if as_points)
        self.particles_as_points += as_points
        return as_points

    def _pieces(self, batch: SplatBatch, view_rotation: np.ndarray, projection: np.ndarray, target_viewport):
        """(the batch's draws, (start, stop, as points), the projection and the viewport they are drawn
        through): with a `target_viewport` (x, y, width, height), the runs of points that
        `cloudcore.particles.point_sprites` allows, through a clip volume wider than the target, the same pixels;
        without one, or when none can be points, the whole batch as quads through `projection` (viewport None)."""
        plain = self._resident.plain_splats(batch) if target_viewport is not None else None
        if plain is None or not plain.any():
            return [(0, len(batch), False)], projection, None
        projection, viewport = guard_band(projection, target_viewport, self._point_sizes_px[1])
        size = (int(viewport[2]), int(viewport[3]))
        fit = point_sprite_mask(
            batch.centres - batch.eye, batch.radii, view_rotation, projection, size, self._point_sizes_px
        )
        return draw_runs(plain & fit), projection, viewport

    def draw_nearest_depth(
        self,
        particles: ParticleBuffer,
        time_s: float,
        chosen: np.ndarray,
        eye: np.ndarray,
        view: np.ndarray,
        projection: np.ndarray,
        height: int,
        core: float = NEAREST_DEPTH_CORE,
    ) -> None:
        """Draw the depth of the `chosen` particles (`nearest_depth_particles`) into the bound target of `height`
        pixels, depth tested and written: each a disc at its centre's depth (its `core`, of its radius), those
        too faint to be seen at `time_s` left out (`NEAREST_DEPTH_OPACITY`); the light shafts' march ends its rays
        at the nearest (docs/atmosphere.md#the-shafts-and-the-air-in-front-of-the-clouds), and Wang's ring's
        panels stand there (its whole discs: `cloudcore.gl.impostor_store`)."""
        if not len(chosen):
            return
        self._resident.hold(particles)
        self._resident.hold_formation(particles, time_s)
        if core not in self._depth_programs:
            program = build_program(
                "cloud_depth",
                {
                    "PARTICLE_FLOATS": PARTICLE_FLOATS,
                    "SEEN_OPACITY": NEAREST_DEPTH_OPACITY,
                    "MAX_POINT_SIZE": self._point_sizes_px[1],
                    "CORE": core,
                },
            )
            self._depth_programs[core] = (
                program,
                uniform_locations(program, ("view_projection", "eye_position", "pixels_per_ndc")),
            )
        program, uniforms = self._depth_programs[core]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_projection"], projection @ view_rotation(view))
        set_vec3_at(uniforms["eye_position"], eye)
        GL.glUniform1f(uniforms["pixels_per_ndc"], 0.5 * height * projection[1, 1])
        store(self._depth_particle_buffer, np.ascontiguousarray(chosen, dtype=np.uint32), GL.GL_STREAM_DRAW)
        bind_storage(
            (0, self._resident.particle_buffer),
            (1, self._resident.formation_buffer),
            (2, self._depth_particle_buffer),
        )
        GL.glBindVertexArray(self._vertex_array)
        GL.glEnable(GL.GL_PROGRAM_POINT_SIZE)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glDrawArrays(GL.GL_POINTS, 0, len(chosen))
        GL.glDisable(GL.GL_PROGRAM_POINT_SIZE)
        GL.glBindVertexArray(0)

    def as_points_in(self, batch: SplatBatch, view: np.ndarray, projection: np.ndarray, viewport) -> tuple | None:
        """(the projection, the viewport) through which all of `batch` is drawn as point sprites into a target
        at `viewport` (x, y, width, height) with its scissor, as `draw` would draw it; None when `draw` would
        draw some of it as quads."""
        if not len(batch):
            return None
        pieces, projection, guarded = self._pieces(batch, view_rotation(view), projection, viewport)
        return (projection, guarded) if pieces == [(0, len(batch), True)] else None

    def draw_point_cells(self, cells) -> None:
        """Draw batches all of point sprites (`as_points_in`), each into its own rectangle of a layered target,
        blended over it without a depth test, as `draw` would one by one: one multi-draw for each
        MAX_VIEWPORTS of them.  `cells`: (batch, view, its projection and viewport from `as_points_in`, the
        scissor rectangle (x, y, width, height), the layer), each shaded ahead (`shade_ahead`) for its view;
        the layered target is bound, its scissor on."""
        if not cells:
            return
        firsts = [self._shading.shaded_ahead(batch, view) for batch, view, *_ in cells]
        if any(first is None for first in firsts):
            raise ValueError("cells drawn together must be shaded ahead for their views (SplatPass.shade_ahead)")
        firsts = np.array(firsts, dtype=np.int32)
        counts = np.array([len(batch) for batch, *_ in cells], dtype=np.int32)
        first_cell = self._use_cells(True, False, [cell[1:6] for cell in cells])
        GL.glEnable(GL.GL_PROGRAM_POINT_SIZE)
        with cloud_blending(depth_test=False, counting=False):
            for start, stop in _viewport_groups(cells, [cell[3] for cell in cells], [cell[4] for cell in cells]):
                GL.glUniform1i(first_cell, start)
                GL.glMultiDrawArrays(GL.GL_POINTS, firsts[start:stop], counts[start:stop], stop - start)
        GL.glDisable(GL.GL_PROGRAM_POINT_SIZE)
        GL.glBindVertexArray(0)
        self.particles_as_points += int(counts.sum())

    def draw_cells(self, selection: SplatSelection, views: np.ndarray, cells) -> None:
        """Draw a selection of many cells (`SplatSelection.cells`), shaded for `views` (one a cell), each cell
        into its own rectangle of a layered target, as quads blended over it without a depth test: one
        indirect multi-draw for each MAX_VIEWPORTS of them, as many particles each as the GPU chose.
        `cells`: per cell (its projection, its viewport and scissor rectangle (x, y, width, height), its
        layer); the layered target is bound, its scissor on."""
        if not selection.slots:
            return
        self._shading.shade(selection, views)
        command = self._order.command(selection)
        with_sprites = self._resident.with_sprites(selection)
        first_cell = self._use_cells(
            False,
            with_sprites,
            [(view, projection, rect, rect, layer) for view, (projection, rect, layer) in zip(views, cells)],
        )
        self._bind_quads(selection.slots)
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, self._order.command_buffer)
        rects = [rect for _, rect, _ in cells]
        with cloud_blending(depth_test=False, counting=False):
            for start, stop in _viewport_groups(cells, rects, rects):
                GL.glUniform1i(first_cell, start)
                GL.glMultiDrawElementsIndirect(
                    GL.GL_TRIANGLES,
                    GL.GL_UNSIGNED_INT,
                    ctypes.c_void_p(4 * COMMAND_UINTS * (command + start)),
                    stop - start,
                    4 * COMMAND_UINTS,
                )
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
        GL.glBindVertexArray(0)
        self._order.drawn(selection, cells=True)

    def _use_cells(self, points: bool, with_sprites: bool, cells) -> int:
        """Make the program drawing many cells current, its table of `cells` (view, projection, viewport,
        scissor, layer) uploaded, the instances bound; returns its first cell's uniform."""
        look = self._look_variant(counting=False)
        key = (points, with_sprites, *look)
        if key not in self._cell_programs:
            defines = _splat_defines(points=points, sprites=with_sprites, look=look, counting=False) | {"CELLS": 1}
            program = build_program("splat", defines)
            self._cell_programs[key] = (program, GL.glGetUniformLocation(program, "first_cell"))
            self._uniforms[program] = uniform_locations(program, _LOOK_UNIFORMS)
        program, first_cell = self._cell_programs[key]
        table = np.zeros((len(cells), _CELL_FLOATS), dtype=np.float32)
        for row, (view, projection, viewport, _, layer) in enumerate(cells):
            # GLSL reads matrices by columns
            table[row, 0:16], table[row, 16:32] = view_rotation(view).T.ravel(), np.asarray(projection).T.ravel()
            table[row, 32:34] = viewport[3], layer
        store(self._cell_buffer, table, GL.GL_STREAM_DRAW)
        GL.glUseProgram(program)
        self._set_look_uniforms(program)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, INSTANCES_BINDING, self._shading.instance_buffer)
        if not self.look.plain:
            GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, TERMS_BINDING, self._shading.terms_buffer)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _CELLS_BINDING, self._cell_buffer)
        GL.glBindVertexArray(self._vertex_array)
        return first_cell

    def _draw_selection(
        self, selection: SplatSelection, view: np.ndarray, projection: np.ndarray, depth_test: bool, counting: bool
    ) -> int:
        """`draw` for particles chosen and ordered on the GPU: as quads, as many as its command counted."""
        if not selection.slots:
            return 0
        self._shading.shade(selection, view)
        command = self._order.command(selection)
        with_sprites = self._resident.with_sprites(selection)
        program = self._program(False, counting, with_sprites, self._look_variant(counting))
        self._use(program, view_rotation(view), projection, None)
        self._bind_quads(selection.slots)
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, self._order.command_buffer)
        with cloud_blending(depth_test, counting):
            GL.glDrawElementsIndirect(GL.GL_TRIANGLES, GL.GL_UNSIGNED_INT, ctypes.c_void_p(4 * COMMAND_UINTS * command))
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
        GL.glBindVertexArray(0)
        if not counting:
            self._order.drawn(selection)
        return 0

    def selected_instances(self, selection: SplatSelection, view: np.ndarray) -> tuple[tuple, tuple]:
        """For a compute pass that composites a selection where the raster would draw it (`cloudcore.gl.
        tile_binning`): (its instances: buffer, first slot, slots; its indirect command's count: buffer, uint
        index), shaded for `view`.  Once composited, `count_drawn` counts its particles."""
        buffer, first = self._shading.shade(selection, view)
        command = self._order.command(selection)
        return (buffer, first, selection.slots), (self._order.command_buffer, COMMAND_UINTS * command)

    def count_drawn(self, selection: SplatSelection) -> None:
        """Count a selection's particles as drawn (`take_selected`) when something else than `draw` drew them."""
        self._order.drawn(selection)

    def read_orders(self, selection: SplatSelection, view: np.ndarray) -> list[np.ndarray]:
        """The particles `selection` chose for `view`'s eye (a view a cell, for cells), far to near, per cell,
        read back from the GPU (to verify them against `splat_batch`: it waits for the GPU)."""
        _, first = self._shading.shade(selection, view)
        command = self._order.command(selection)
        counts = self._order.command_counts(command + selection.cell_count)[command:]
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, self._shading.order_buffer)
        size = 4 * selection.slots
        order = np.frombuffer(
            GL.glGetBufferSubData(GL.GL_COPY_READ_BUFFER, 4 * first, size) if size else b"", np.uint32
        )
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, 0)
        return [order[start : start + count].copy() for start, count in zip(selection.cell_slots()[0], counts)]

    def _use(self, program: int, view_rotation: np.ndarray, projection: np.ndarray, viewport_height) -> None:
        """Make `program` current with a draw's matrices (and, for points, the viewport's height in pixels)."""
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_rotation"], view_rotation)
        set_matrix_at(uniforms["projection"], projection)
        if viewport_height is not None:
            GL.glUniform1f(uniforms["viewport_height"], viewport_height)
        self._set_look_uniforms(program)

    def _set_look_uniforms(self, program: int) -> None:
        """The detail noise's amplitude and scale, where `program` (current) has them."""
        uniforms = self._uniforms[program]
        if uniforms["detail_amplitude"] >= 0:
            GL.glUniform1f(uniforms["detail_amplitude"], self.look.detail_noise)
            GL.glUniform1f(uniforms["detail_scale"], self.look.detail_noise_scale_m)

    def _bind_quads(self, count: int) -> None:
        """Bind what drawing `count` particles' quads reads: the atlas, the instances, the triangles."""
        if self._resident.atlas is not None:
            GL.glActiveTexture(GL.GL_TEXTURE0)
            GL.glBindTexture(GL.GL_TEXTURE_2D, self._resident.atlas)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, INSTANCES_BINDING, self._shading.instance_buffer)
        if not self.look.plain:
            GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, TERMS_BINDING, self._shading.terms_buffer)
        GL.glBindVertexArray(self._vertex_array)
        self._index_quads(count)

    def _index_quads(self, count: int) -> None:
        """Grow the (bound vertex array's) element buffer to hold the triangles of `count` particles."""
        if count <= self._quads_indexed:
            return
        count = max(count, 2 * self._quads_indexed)  # grow geometrically: few reallocations on a long path
        indices = (_QUAD_TRIANGLES[None, :] + 4 * np.arange(count, dtype=np.uint32)[:, None]).ravel()
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self._corner_index_buffer)
        GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_STATIC_DRAW)
        self._quads_indexed = count

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        for program in self._programs.values():
            GL.glDeleteProgram(program)
        for program, _ in self._cell_programs.values():
            GL.glDeleteProgram(program)
        for program, _ in self._depth_programs.values():
            GL.glDeleteProgram(program)
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))
        GL.glDeleteVertexArrays(1, [self._vertex_array])
        self._shading.close()
        self._order.close()
        self._resident.close()


def _splat_defines(*, points: bool, sprites: bool, look: tuple[bool, bool], counting: bool) -> dict:
    """splat.vert.glsl's and splat.frag.glsl's defines for a draw of points or quads, with atlas sprites or not, in
    the look variant `look` (per pixel?, detail noise?), counting fragments or not."""
    per_pixel, noise = look
    variant = {
        "POINT_SPRITE": points,
        "COUNT_FRAGMENTS": counting,
        "ATLAS_SPRITES": sprites,
        "PIXEL_LOOK": per_pixel or noise,
        "PER_PIXEL": per_pixel,
        "DETAIL_NOISE": noise,
    }
    constants = {"SPLAT_SHARPNESS": SPLAT_SHARPNESS, "ATLAS_GRID": ATLAS_GRID}
    if per_pixel or noise:
        constants |= {"KERNEL_DIAMETER_INTEGRAL": KERNEL_DIAMETER_INTEGRAL, "MAX_OPACITY": MAX_OPACITY}
    return constants | {name: 1 for name, on in variant.items() if on}


def _viewport_groups(cells, viewports, scissors):
    """(start, stop) of each run of at most MAX_VIEWPORTS `cells`, their `viewports` and `scissors` (x, y,
    width, height) set as the indexed viewports and scissors of one multi-draw."""
    for start in range(0, len(cells), _MAX_VIEWPORTS):
        stop = min(start + _MAX_VIEWPORTS, len(cells))
        GL.glViewportArrayv(0, stop - start, np.array(viewports[start:stop], dtype=np.float32))
        GL.glScissorArrayv(0, stop - start, np.array(scissors[start:stop], dtype=np.int32))
        yield start, stop
