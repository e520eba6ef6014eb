"""Splats: particles as instanced camera-facing billboards, blended back to front.

The particles stay on the GPU: `SplatPass` uploads a `ParticleBuffer`'s
per-particle terms (centre, radius, scattering, ambient, incident light per
light; for Yusov's eye pass, the row of its light-leaving profiles, which
go in a buffer of their own) once, into storage buffers, and a compute shader colours each
particle of a draw for the eye (Harris eq. 5) into the instance attributes
the splats are drawn from.  Per draw the CPU only orders:
`splat_batch` gathers the particles of some clouds (several together, since
clouds interpenetrate in depth), leaves out those the near fade or a
formation makes fully transparent, and sorts the rest far to near from the
eye; the batch uploads just those indices (4 bytes a particle).  Or, for
a `SplatSelection`, the GPU does that too (`splat_select.comp.glsl`, then
`cloudcore.gl.depth_sort`) and the quads are drawn by an indirect draw whose
count the GPU wrote: the CPU's work for the draw no longer grows with its
particles.  One selection may hold many draws from one eye, each into its own
cell of a layered target (a frame's impostor regenerations): chosen in one
dispatch, sorted by distance then by cell in one sort, drawn by one indirect
multi-draw a 16 cells.  With the depth test on, terrain hides splats; splats never write
depth.  Drawn with `counting=True`, every fragment adds 1 instead (overdraw).
"""

from __future__ import annotations

import ctypes
import itertools
from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.artist.facing import FacingState
from cloudcore.artist.particle_styles import FACING_SPLAT, ParticleStyles
from cloudcore.artist.sprites import ATLAS_MAX_MIP_LEVEL, load_atlas
from cloudcore.cloud_records import ATLAS_GRID
from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.blending import cloud_blending
from cloudcore.gl.depth_sort import GpuDepthSort, key_bits_for
from cloudcore.gl.programs import (
    build_compute_program,
    build_program,
    dispatch,
    set_matrix_at,
    set_vec3_at,
    uniform_locations,
)
from cloudcore.light.eye_scattering import FADE_END_RADII, FADE_START_RADII, ParticleBuffer
from cloudcore.light.phase import PHASE_NAMES
from cloudcore.limits import MAX_LIGHTS
from cloudcore.lod.depth_order import far_to_near
from cloudcore.point_sprites import draw_runs, guard_band, plain_splats, point_sprite_mask
from cloudcore.splat_coverage import splats_in_frustum
from cloudcore.splat_kernel import SPLAT_REACH, SPLAT_SHARPNESS
from cloudcore.vectors import row_lengths

#: two triangles over a particle's four corners (lower left, lower right, upper left, upper right)
_QUAD_TRIANGLES = np.array([0, 1, 2, 2, 1, 3], dtype=np.uint32)
#: lights the shader sums over; more would only add light too faint to matter (skylights share the sky)
#: the shader's `Particle` in std430 layout: five vec4 then MAX_LIGHTS floats
_PARTICLE_FLOATS = 20 + MAX_LIGHTS
#: the shader's `CloudStyle`: ten vec4
_CLOUD_FLOATS = 40
#: per particle, written by the compute shader: four corners and four colours (vec4 each)
INSTANCE_BYTES = 8 * 16
_UNLOCKED = (0.0, 0.0, 0.0, -1.0)
(
    _PARTICLES_BINDING,
    _FORMATION_BINDING,
    _ORDER_BINDING,
    _INSTANCES_BINDING,
    _CLOUDS_BINDING,
    _FACING_BINDING,
    _PROFILES_BINDING,
    _BATCHES_BINDING,
) = range(8)
#: floats of splat_shade.comp.glsl's `Batch`: first slot and count (as uints), eye, image plane's right and up
_BATCH_FLOATS = 16
#: splat.vert.glsl's `Cell` (CELLS): view rotation, projection, viewport height and layer; its binding
_CELL_FLOATS = 36
_CELLS_BINDING = 8
#: viewports (and scissors) a multi-draw of cells can address: what GL 4.1 guarantees, llvmpipe's and NVIDIA's
_MAX_VIEWPORTS = 16
#: splat_select.comp.glsl's buffers
(
    _SELECT_PARTICLES,
    _SELECT_FORMATION,
    _SELECT_BITS,
    _SELECT_RANGES,
    _SELECT_KEYS,
    _SELECT_VALUES,
    _SELECT_COMMAND,
    _SELECT_ORDER,
) = range(8)
#: uints of splat_select.comp.glsl's `Range`: first particle, slots before, depth range, cell, three unused
_RANGE_UINTS = 8
#: the compute shaders' local_size_x
_SHADE_GROUP = _SELECT_GROUP = 64
#: uints of a DrawElementsIndirectCommand: count, instance count, first index, base vertex, base instance
_COMMAND_UINTS = 5


@dataclass(frozen=True)
class SplatBatch:
    """Particles of one draw, far to near from `eye`, as indices into `particles`."""

    particles: ParticleBuffer
    order: np.ndarray  # (n,) uint32
    eye: np.ndarray
    time_s: float | None
    #: whether its colours take the air between `eye` and each particle (`SplatPass.air`): the cloud pass's
    #: draws, not an impostor's, whose texture is seen from elsewhere
    through_air: bool = False

    def __len__(self) -> int:
        return len(self.order)

    @property
    def slots(self) -> int:
        """Instances its shading fills."""
        return len(self.order)

    def on_cpu(self) -> SplatBatch:
        """The batch (its particles are known on the CPU): as `SplatSelection.on_cpu`."""
        return self

    @property
    def centres(self) -> np.ndarray:
        """(n, 3) world centres, for the analytic overdraw estimate."""
        return self.particles.centres[self.order]

    @property
    def radii(self) -> np.ndarray:
        return self.particles.radii[self.order]


@dataclass(frozen=True, eq=False)
class SplatSelection:
    """The particles of one draw as `splat_batch` chooses them (its arguments), chosen and ordered by the GPU
    when `SplatPass` shades it: how many there are is known there only (`SplatPass.take_selected`).

    With `cells`, per cloud the draw its particles go to, from 0 up and non-decreasing: many draws from one
    eye, one into each cell of a layered target (`SplatPass.draw_cells`), chosen in one dispatch and
    sorted in one sort; shaded for one view a cell."""

    particles: ParticleBuffer
    clouds: tuple
    eye: np.ndarray
    depth_ranges: tuple | None
    time_s: float | None
    frustum: np.ndarray | None
    cells: tuple | None = None
    through_air: bool = False  # as `SplatBatch.through_air`

    def __post_init__(self):
        if self.cells is not None and (
            len(self.cells) != len(self.clouds)
            or (self.cells and self.cells[0] != 0)
            or np.any(np.diff(self.cells) < 0)
        ):
            raise ValueError(f"a selection's cells go from 0 up, one a cloud, got {self.cells} for {self.clouds}")

    @property
    def slots(self) -> int:
        """Instances its shading fills: one per particle of its clouds, chosen or not."""
        return int(self._counts.sum())

    @property
    def cell_count(self) -> int:
        return 1 if self.cells is None else (self.cells[-1] + 1 if self.cells else 0)

    def cell_slots(self) -> tuple[np.ndarray, np.ndarray]:
        """(each cell's first slot from the selection's first, the slots it holds): the particles of its clouds."""
        cells = np.zeros(len(self.clouds), dtype=np.int64) if self.cells is None else np.asarray(self.cells)
        held = np.bincount(cells, weights=self._counts, minlength=self.cell_count).astype(np.int64)
        return np.cumsum(held) - held, held

    @property
    def _counts(self) -> np.ndarray:
        starts = self.particles.cloud_starts
        clouds = np.asarray(self.clouds, dtype=np.int64)
        return (starts[clouds + 1] - starts[clouds]) if len(clouds) else np.zeros(0, dtype=np.int64)

    def on_cpu(self) -> SplatBatch:
        """The same particles chosen and sorted on the CPU, for what reads them there (overdraw's estimate)."""
        return splat_batch(
            self.particles, self.clouds, self.eye, self.depth_ranges, self.time_s, self.frustum, self.through_air
        )


def splat_batch(
    particles: ParticleBuffer,
    clouds,
    eye,
    depth_ranges=None,
    time_s: float | None = None,
    frustum: np.ndarray | None = None,
    through_air: bool = False,
) -> SplatBatch:
    """The visible particles of `clouds` (indices), sorted far to near from `eye`.

    `depth_ranges`, one (near, far) per cloud, keeps only the particles with
    near < distance from `eye` <= far: one layer of a cloud split around objects.
    `time_s`, the scene clock, fades forming and dissipating clouds (`ParticleBuffer.seen_from`), and
    the buffer's blend weights fade a cloud field's rings.
    `frustum`, the draw's planes (`cloudcore.camera.frustum_planes`), leaves out the splats outside it.
    `through_air`: `SplatBatch.through_air`.
    """
    starts = particles.cloud_starts
    # a cloud's particles are contiguous: slices gather them faster than an index array does
    pieces = [slice(starts[c], starts[c + 1]) for c in clouds]
    counts = [piece.stop - piece.start for piece in pieces]
    indices = np.concatenate([np.arange(piece.start, piece.stop) for piece in pieces]) if pieces else np.zeros(0, int)
    centres = np.concatenate([particles.centres[piece] for piece in pieces]) if pieces else np.zeros((0, 3))
    eye = np.asarray(eye, dtype=np.float64)
    offsets = centres - eye
    distances = row_lengths(offsets)
    kept = particles.drawn(indices, distances, time_s)
    if depth_ranges is not None:
        near = np.repeat([r[0] for r in depth_ranges], counts)
        far = np.repeat([r[1] for r in depth_ranges], counts)
        kept &= (distances > near) & (distances <= far)
    if frustum is not None:
        radii = np.concatenate([particles.radii[piece] for piece in pieces]) if pieces else np.zeros(0)
        kept &= splats_in_frustum(frustum, centres, radii)
    indices, distances = indices[kept], distances[kept]
    return SplatBatch(particles, indices[far_to_near(distances)].astype(np.uint32), eye, time_s, through_air)


#: a batch's instances start at a multiple of this many slots: 256 bytes, the largest offset alignment of a
#: storage buffer range GL allows, so that any batch's can be bound alone
_SLOT_ALIGNMENT = 256 // INSTANCE_BYTES


def _slots(count: int) -> int:
    """Slots a batch of `count` particles takes, its start aligned."""
    return -(-count // _SLOT_ALIGNMENT) * _SLOT_ALIGNMENT


#: splat_shade.comp.glsl's optional code, in the order of a variant's key: sprites that do not lie in the
#: image plane, Wang's artist colours, Yusov's eye-pass profiles
_SHADE_FEATURES = ("FACING", "ARTIST", "PROFILES", "AIR")


class SplatPass:
    def __init__(self):
        defines = {"SPLAT_SHARPNESS": SPLAT_SHARPNESS, "ATLAS_GRID": ATLAS_GRID}
        variants = {"POINT_SPRITE": (False, True), "COUNT_FRAGMENTS": (False, True), "ATLAS_SPRITES": (False, True)}
        #: (points?, counting?, atlas sprites?) -> program; a point is never a sprite
        self._programs = {
            key: build_program("splat", defines | {name: 1 for name, on in zip(variants, key) if on})
            for key in itertools.product(*variants.values())
            if not (key[0] and key[2])
        }
        #: per program, the locations of the uniforms every draw sets
        self._uniforms = {
            program: uniform_locations(program, ("view_rotation", "projection", "viewport_height"))
            for program in self._programs.values()
        }
        self._point_sizes_px = tuple(float(size) for size in GL.glGetFloatv(GL.GL_POINT_SIZE_RANGE))
        self._plain: np.ndarray = np.zeros(0, dtype=bool)  # of the resident particles: `plain_splats`
        self._cloud_plain: np.ndarray = np.zeros(0, dtype=bool)  # of their clouds: all particles plain
        self._sprites: np.ndarray = np.zeros(0, dtype=bool)  # of the resident particles: drawn from the atlas
        #: of the resident particles: per particle, (facing, artist) as bits; whether there are Yusov's profiles
        self._feature_bits: np.ndarray = np.zeros(0, dtype=np.uint8)
        self._profiled = False
        #: particles drawn as point sprites since the frame's renderer last set it to 0 (for its statistics)
        self.particles_as_points = 0
        #: the compute shader's variants by the features a batch has (`_SHADE_FEATURES`), made when first
        #: needed: (program, its uniforms' locations, the particles its light uniforms are of)
        self._shade_programs: dict[tuple, list] = {}
        #: the frame's air (`cloudcore.gl.air_volume`), uploaded for its eye, which batches `through_air` take;
        #: None: no air (the gradient sky)
        self.air: AirVolume | None = None
        self._vertex_array = GL.glGenVertexArrays(1)
        (
            self._corner_index_buffer,
            self._order_buffer,
            self._instance_buffer,
            self._particle_buffer,
            self._formation_buffer,
            self._cloud_buffer,
            self._facing_buffer,
            self._profile_buffer,
            self._batch_buffer,
            self._cell_buffer,
        ) = self._buffers = GL.glGenBuffers(10)
        self._atlas: int | None = None  # the sprite atlas texture, made when a cloud first needs it
        self._quads_indexed = 0
        self._instance_capacity = 0  # slots
        #: the batches the pass shaded ahead (`shade_ahead`): id -> (first slot, the view they were shaded
        #: for, the batch, kept so that its id stays its own); and the slots they fill, after which any
        #: other batch is shaded as it is drawn
        self._shaded: dict[int, tuple[int, np.ndarray, SplatBatch]] = {}
        self._slots_ahead = 0
        self._resident: ParticleBuffer | None = None
        self._formation_time: tuple | None = None  # (time, weights serial) of the held opacity factors
        #: of the resident particles' clouds: (facing, artist) as bits, whether any is an atlas sprite; what a
        #: `SplatSelection`'s shading and drawing go by, its particles unknown to the CPU
        self._cloud_feature_bits: np.ndarray = np.zeros(1, dtype=np.uint8)
        self._cloud_sprites: np.ndarray = np.zeros(1, dtype=bool)
        #: choosing and sorting on the GPU, made when a selection first needs it: (splat_select's program,
        #: its uniforms' locations, the sort)
        self._selecting: tuple | None = None
        (
            self._drawn_bits_buffer,
            self._ranges_buffer,
            self._keys_buffer,
            self._values_buffer,
            self._command_buffer,
        ) = self._selection_buffers = GL.glGenBuffers(5)
        self._keys_capacity = self._command_capacity = 0
        #: the selections shaded since `shade_ahead` last began a pass: id -> their first indirect command's
        #: index (one a cell); the commands made since `take_selected`, which begins them again from 0
        self._commands: dict[int, int] = {}
        self._commands_made = 0
        #: commands drawn (not counting fragments) since `take_selected`: into the target, into cells
        self._drawn_commands: list[int] = []
        self._drawn_cell_commands: list[int] = []
        #: the programs drawing many cells at once, made when first needed: (points?, atlas sprites?) -> (the
        #: program, its first cell's uniform); points never are sprites
        self._cell_programs: dict[tuple[bool, bool], tuple[int, int]] = {}

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

        With `point_sprites`, the runs of the batch that `cloudcore.point_sprites` allows are drawn as
        points, the rest as quads, in the batch's order; returns the particles drawn as points.
        A `SplatSelection` is drawn as quads, by one indirect draw.
        """
        if isinstance(batch, SplatSelection):
            return self._draw_selection(batch, view, projection, depth_test, counting)
        if not len(batch):
            return 0
        _, first = self.shade(batch, view)
        view_rotation = _rotation(view)
        target_viewport = GL.glGetIntegerv(GL.GL_VIEWPORT) if point_sprites else None
        pieces, projection, viewport = self._pieces(batch, view_rotation, projection, target_viewport)
        if viewport is not None:
            GL.glViewport(*viewport)
        with_sprites = bool(self._sprites[batch.order].any())
        programs = {points: self._programs[points, counting, with_sprites and not points] for points in (False, True)}
        for as_points in {piece[2] for piece in pieces}:
            self._use(programs[as_points], view_rotation, projection, float(viewport[3]) if as_points else None)
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
        `cloudcore.point_sprites` allows, through a clip volume wider than the target, the same pixels; without
        one, or when none can be points, the whole batch as quads through `projection` (viewport None)."""
        plain = self.plain_splats(batch) if target_viewport is not None else None
        if plain is None or not plain.any():
            return [(0, len(batch), False)], projection, None
        projection, viewport = guard_band(projection, target_viewport, self._point_sizes_px[1])
        size = (int(viewport[2]), int(viewport[3]))
        fit = point_sprite_mask(
            batch.centres - batch.eye, batch.radii, view_rotation, projection, size, self._point_sizes_px
        )
        return draw_runs(plain & fit), projection, viewport

    def as_points_in(self, batch: SplatBatch, view: np.ndarray, projection: np.ndarray, viewport) -> tuple | None:
        """(the projection, the viewport) through which all of `batch` is drawn as point sprites into a target
        at `viewport` (x, y, width, height) with its scissor, as `draw` would draw it; None when `draw` would
        draw some of it as quads."""
        if not len(batch):
            return None
        pieces, projection, guarded = self._pieces(batch, _rotation(view), projection, viewport)
        return (projection, guarded) if pieces == [(0, len(batch), True)] else None

    def draw_point_cells(self, cells) -> None:
        """Draw batches all of point sprites (`as_points_in`), each into its own rectangle of a layered target,
        blended over it without a depth test, as `draw` would one by one: one multi-draw for each
        MAX_VIEWPORTS of them.  `cells`: (batch, view, its projection and viewport from `as_points_in`, the
        scissor rectangle (x, y, width, height), the layer), each shaded ahead (`shade_ahead`) for its view;
        the layered target is bound, its scissor on."""
        if not cells:
            return
        shaded = [self._shaded.get(id(batch)) for batch, *_ in cells]
        if any(held is None or not np.array_equal(held[1], view) for held, (_, view, *_) in zip(shaded, cells)):
            raise ValueError("cells drawn together must be shaded ahead for their views (SplatPass.shade_ahead)")
        firsts = np.array([held[0] for held in shaded], dtype=np.int32)
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
        self.shade(selection, views)
        command = self._commands[id(selection)]
        with_sprites = bool(self._cloud_sprites[list(selection.clouds)].any())
        first_cell = self._use_cells(
            False,
            with_sprites,
            [(view, projection, rect, rect, layer) for view, (projection, rect, layer) in zip(views, cells)],
        )
        self._bind_quads(selection.slots)
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, self._command_buffer)
        rects = [rect for _, rect, _ in cells]
        with cloud_blending(depth_test=False, counting=False):
            for start, stop in _viewport_groups(cells, rects, rects):
                GL.glUniform1i(first_cell, start)
                GL.glMultiDrawElementsIndirect(
                    GL.GL_TRIANGLES,
                    GL.GL_UNSIGNED_INT,
                    ctypes.c_void_p(4 * _COMMAND_UINTS * (command + start)),
                    stop - start,
                    4 * _COMMAND_UINTS,
                )
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
        GL.glBindVertexArray(0)
        self._drawn_cell_commands.extend(range(command, command + selection.cell_count))

    def _use_cells(self, points: bool, with_sprites: bool, cells) -> int:
        """Make the program drawing many cells current, its table of `cells` (view, projection, viewport,
        scissor, layer) uploaded, the instances bound; returns its first cell's uniform."""
        key = (points, with_sprites)
        if key not in self._cell_programs:
            variant = {"POINT_SPRITE": points, "ATLAS_SPRITES": with_sprites}
            program = build_program(
                "splat",
                {"SPLAT_SHARPNESS": SPLAT_SHARPNESS, "ATLAS_GRID": ATLAS_GRID, "CELLS": 1}
                | {name: 1 for name, on in variant.items() if on},
            )
            self._cell_programs[key] = (program, GL.glGetUniformLocation(program, "first_cell"))
        program, first_cell = self._cell_programs[key]
        table = np.zeros((len(cells), _CELL_FLOATS), dtype=np.float32)
        for row, (view, projection, viewport, _, layer) in enumerate(cells):
            # GLSL reads matrices by columns
            table[row, 0:16], table[row, 16:32] = _rotation(view).T.ravel(), np.asarray(projection).T.ravel()
            table[row, 32:34] = viewport[3], layer
        _store(self._cell_buffer, table, GL.GL_STREAM_DRAW)
        GL.glUseProgram(program)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _INSTANCES_BINDING, self._instance_buffer)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _CELLS_BINDING, self._cell_buffer)
        GL.glBindVertexArray(self._vertex_array)
        return first_cell

    def _draw_selection(
        self, selection: SplatSelection, view: np.ndarray, projection: np.ndarray, depth_test: bool, counting: bool
    ) -> int:
        """`draw` for particles chosen and ordered on the GPU: as quads, as many as its command counted."""
        if not selection.slots:
            return 0
        self.shade(selection, view)
        command = self._commands[id(selection)]
        with_sprites = bool(self._cloud_sprites[list(selection.clouds)].any())
        self._use(self._programs[False, counting, with_sprites], _rotation(view), projection, None)
        self._bind_quads(selection.slots)
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, self._command_buffer)
        with cloud_blending(depth_test, counting):
            GL.glDrawElementsIndirect(
                GL.GL_TRIANGLES, GL.GL_UNSIGNED_INT, ctypes.c_void_p(4 * _COMMAND_UINTS * command)
            )
        GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
        GL.glBindVertexArray(0)
        if not counting:
            self._drawn_commands.append(command)
        return 0

    def selected_instances(self, selection: SplatSelection, view: np.ndarray) -> tuple[tuple, tuple]:
        """For a compute pass that composites a selection where the raster would draw it (`cloudcore.gl.
        tile_binning`): (its instances: buffer, first slot, slots; its indirect command's count: buffer, uint
        index), shaded for `view`.  Once composited, `count_drawn` counts its particles."""
        buffer, first = self.shade(selection, view)
        command = self._commands[id(selection)]
        return (buffer, first, selection.slots), (self._command_buffer, _COMMAND_UINTS * command)

    def count_drawn(self, selection: SplatSelection) -> None:
        """Count a selection's particles as drawn (`take_selected`) when something else than `draw` drew them."""
        self._drawn_commands.append(self._commands[id(selection)])

    def plain_selection(self, selection: SplatSelection) -> bool:
        """Whether every particle of a selection's clouds is a plain Gaussian splat of one colour
        (`cloudcore.point_sprites.plain_splats`): what a compute pass can composite."""
        self._make_resident(selection.particles)
        return bool(np.all(self._cloud_plain[list(selection.clouds)]))

    def take_selected(self) -> tuple[int, int]:
        """(the particles that the selections drawn into targets since the last call chose, those drawn into
        cells), read from their commands (after the draws finished, this waits for nothing); the commands
        are made from the first again."""
        drawn = self._drawn_commands + self._drawn_cell_commands
        counts = self._command_counts(max(drawn) + 1) if drawn else np.zeros(0, dtype=np.int64)
        taken = tuple(int(counts[commands].sum()) for commands in (self._drawn_commands, self._drawn_cell_commands))
        self._drawn_commands, self._drawn_cell_commands, self._commands_made = [], [], 0
        return taken

    def read_orders(self, selection: SplatSelection, view: np.ndarray) -> list[np.ndarray]:
        """The particles `selection` chose for `view`'s eye (a view a cell, for cells), far to near, per cell,
        read back from the GPU (to verify them against `splat_batch`: it waits for the GPU)."""
        _, first = self.shade(selection, view)
        command = self._commands[id(selection)]
        counts = self._command_counts(command + selection.cell_count)[command:]
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, self._order_buffer)
        size = 4 * selection.slots
        order = np.frombuffer(
            GL.glGetBufferSubData(GL.GL_COPY_READ_BUFFER, 4 * first, size) if size else b"", np.uint32
        )
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, 0)
        return [order[start : start + count].copy() for start, count in zip(selection.cell_slots()[0], counts)]

    def _command_counts(self, commands: int) -> np.ndarray:
        """The particles the first `commands` indirect commands count (reading them waits for the GPU)."""
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, self._command_buffer)
        size = 4 * _COMMAND_UINTS * commands
        records = np.frombuffer(GL.glGetBufferSubData(GL.GL_COPY_READ_BUFFER, 0, size), dtype=np.uint32)
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, 0)
        return records.reshape(-1, _COMMAND_UINTS)[:, 0].astype(np.int64) // 6

    def _use(self, program: int, view_rotation: np.ndarray, projection: np.ndarray, viewport_height) -> None:
        """Make `program` current with a draw's matrices (and, for points, the viewport's height in pixels)."""
        uniforms = self._uniforms[program]
        GL.glUseProgram(program)
        set_matrix_at(uniforms["view_rotation"], view_rotation)
        set_matrix_at(uniforms["projection"], projection)
        if viewport_height is not None:
            GL.glUniform1f(uniforms["viewport_height"], viewport_height)

    def _bind_quads(self, count: int) -> None:
        """Bind what drawing `count` particles' quads reads: the atlas, the instances, the triangles."""
        if self._atlas is not None:
            GL.glActiveTexture(GL.GL_TEXTURE0)
            GL.glBindTexture(GL.GL_TEXTURE_2D, self._atlas)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _INSTANCES_BINDING, self._instance_buffer)
        GL.glBindVertexArray(self._vertex_array)
        self._index_quads(count)

    def plain_splats(self, batch: SplatBatch) -> np.ndarray:
        """(n,) bool: which of the batch's particles are plain Gaussian splats of one colour
        (`cloudcore.point_sprites.plain_splats`)."""
        self._make_resident(batch.particles)
        return self._plain[batch.order]

    def _index_quads(self, count: int) -> None:
        """Grow the (bound vertex array's) element buffer to hold the triangles of `count` particles."""
        if count <= self._quads_indexed:
            return
        count = max(count, 2 * self._quads_indexed)  # grow geometrically: few reallocations on a long path
        indices = (_QUAD_TRIANGLES[None, :] + 4 * np.arange(count, dtype=np.uint32)[:, None]).ravel()
        GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self._corner_index_buffer)
        GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_STATIC_DRAW)
        self._quads_indexed = count

    def update_facing(self, particles: ParticleBuffer, start: int, state: FacingState) -> None:
        """The facing lock of particles `start`, `start + 1`, ... (one cloud's) for the next draws."""
        self._make_resident(particles)
        records = np.empty((len(state.fade), 4), dtype=np.float32)
        records[:, :3] = state.normals
        records[:, 3] = np.where(state.locked, state.fade, _UNLOCKED[3])
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._facing_buffer)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, start * records.itemsize * 4, records.nbytes, records)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)

    def shade_ahead(self, batches_and_views) -> None:
        """Shade the (batch, view) pairs a pass will draw, one after the other before any of its draws, and
        forget those shaded before: `draw` and `shade` then find them shaded.

        The compute shader's results need a memory barrier before a draw reads them, and llvmpipe makes
        each barrier a glFinish: shaded draw by draw, every batch waited for the draws before it.
        """
        self._shaded, self._slots_ahead, self._commands = {}, 0, {}
        batches_and_views = [(batch, view) for batch, view in batches_and_views if batch.slots]
        if not batches_and_views:
            return
        self._reserve(sum(_slots(batch.slots) for batch, _ in batches_and_views), keep=False)
        firsts = self._shade_all(batches_and_views, 0)
        for (batch, view), first in zip(batches_and_views, firsts):
            self._shaded[id(batch)] = (first, np.array(view, dtype=np.float64), batch)
        self._slots_ahead = sum(_slots(batch.slots) for batch, _ in batches_and_views)
        GL.glMemoryBarrier(_SHADED_BARRIERS)

    def shade(self, batch: SplatBatch, view: np.ndarray) -> tuple[int, int]:
        """(the storage buffer holding the batch's quads and colours for its eye, in its order, the slot of
        its first): those `shade_ahead` made, else shaded now after them (the volume-aware blending pass
        reads them too)."""
        shaded = self._shaded.get(id(batch))
        if shaded is not None and np.array_equal(shaded[1], view):
            return self._instance_buffer, shaded[0]
        self._reserve(self._slots_ahead + _slots(batch.slots), keep=True)
        self._shade_all([(batch, view)], self._slots_ahead)
        GL.glMemoryBarrier(_SHADED_BARRIERS)
        return self._instance_buffer, self._slots_ahead

    def _reserve(self, slots: int, keep: bool) -> None:
        """Room for `slots` instances (and their order), growing geometrically; `keep`: with the instances
        shaded so far, which draws to come may still read."""
        if slots <= self._instance_capacity:
            return
        capacity = max(slots, 2 * self._instance_capacity)
        kept = self._slots_ahead * INSTANCE_BYTES if keep else 0
        # the buffer keeps its name (draws and the volume pass bind it by name): what is kept goes through a
        # scratch copy while it is reallocated; growing happens a few times a session
        scratch = GL.glGenBuffers(1) if kept else None
        if kept:
            _copy_buffer(self._instance_buffer, scratch, kept, allocate=True)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._instance_buffer)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, capacity * INSTANCE_BYTES, None, GL.GL_DYNAMIC_COPY)
        if kept:
            _copy_buffer(scratch, self._instance_buffer, kept, allocate=False)
            GL.glDeleteBuffers(1, [scratch])
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._order_buffer)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, capacity * 4, None, GL.GL_STREAM_DRAW)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        self._instance_capacity = capacity

    def _shade_all(self, batches_and_views, first: int) -> list[int]:
        """Shade the (batch, view) pairs (room reserved) into the slots from `first` on, each batch's start
        aligned; returns each one's first slot.  All the CPU's orders go up in one upload, and each run of
        batches with the same particles, scene time and shader variant is one dispatch."""
        runs: dict[tuple, list] = {}  # key -> [[batch, view, first slot]], slots contiguous within a run
        for batch, view in batches_and_views:
            runs.setdefault((id(batch.particles), batch.time_s, self._features(batch)), []).append([batch, view])
        firsts, end = {}, first
        for run in runs.values():
            for entry in run:
                entry.append(end)
                firsts[id(entry[0])] = end
                end += _slots(entry[0].slots)
        orders = np.zeros(end - first, dtype=np.uint32)
        for run in runs.values():
            for batch, _, slot in run:
                if isinstance(batch, SplatBatch):
                    orders[slot - first : slot - first + len(batch)] = batch.order
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._order_buffer)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, first * 4, orders.nbytes, orders)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        for (_, _, features), run in runs.items():
            self._dispatch(run, features)
        return [firsts[id(batch)] for batch, _ in batches_and_views]

    def _dispatch(self, run: list, features: tuple) -> None:
        """Shade a run of (batch, view, first slot), their order uploaded, in one dispatch of the variant with
        `features` (selections are chosen and sorted first)."""
        particles, time_s = run[0][0].particles, run[0][0].time_s
        self._make_resident(particles)
        self._hold_formation(particles, time_s)
        for batch, _, slot in run:
            if isinstance(batch, SplatSelection):
                self._select(batch, slot)
        rows = []  # (first slot, slots, eye, view): a batch's, a cell's of a selection of cells
        for batch, view, slot in run:
            if isinstance(batch, SplatSelection) and batch.cells is not None:
                firsts, held = batch.cell_slots()
                rows.extend((slot + first, count, batch.eye, cell) for first, count, cell in zip(firsts, held, view))
            else:
                rows.append((slot, batch.slots, batch.eye, view))
        table = np.zeros((len(rows), _BATCH_FLOATS), dtype=np.float32)
        slots = table.view(np.uint32)
        for row, (slot, count, eye, view) in enumerate(rows):
            slots[row, 0:2] = slot, count
            table[row, 4:7], table[row, 8:11], table[row, 12:15] = eye, view[0, :3], view[1, :3]
        _store(self._batch_buffer, table, GL.GL_STREAM_DRAW)
        _bind_storage(
            (_PARTICLES_BINDING, self._particle_buffer),
            (_FORMATION_BINDING, self._formation_buffer),
            (_ORDER_BINDING, self._order_buffer),
            (_INSTANCES_BINDING, self._instance_buffer),
            (_CLOUDS_BINDING, self._cloud_buffer),
            (_FACING_BINDING, self._facing_buffer),
            (_PROFILES_BINDING, self._profile_buffer),
            (_BATCHES_BINDING, self._batch_buffer),
        )
        program, uniforms = self._shade_program(features)
        first, end = run[0][2], run[-1][2] + run[-1][0].slots
        GL.glUseProgram(program)
        if features[_SHADE_FEATURES.index("AIR")]:
            self.air.bind(program)
        GL.glUniform1ui(uniforms["first"], first)
        GL.glUniform1ui(uniforms["slot_count"], end - first)
        GL.glUniform1ui(uniforms["batch_count"], len(rows))
        dispatch(-(-(end - first) // _SHADE_GROUP))

    def _select(self, selection: SplatSelection, first: int) -> None:
        """Choose and sort `selection`'s particles on the GPU into the order's slots from `first` on, each cell's
        from its first slot on (`SplatSelection.cell_slots`), the chosen first, far to near, and count them
        into a new indirect command of quads a cell."""
        if self._selecting is None:
            defines = {
                "PARTICLE_FLOATS": _PARTICLE_FLOATS,
                "FADE_START_RADII": FADE_START_RADII,
                "SPLAT_REACH": SPLAT_REACH,
                "COMMAND_UINTS": _COMMAND_UINTS,
            }
            program = build_compute_program("splat_select", defines)
            names = ("count", "range_count", "command_at", "eye", "planes", "cull_to_frustum")
            resolve = build_compute_program("splat_select", defines | {"RESOLVE": 1})
            resolving = uniform_locations(resolve, ("count", "range_count", "cell_keys", "first"))
            self._selecting = (program, uniform_locations(program, names), GpuDepthSort(), resolve, resolving)
        program, uniforms, sort = self._selecting[:3]
        slots, command, cells = selection.slots, self._commands_made, selection.cell_count
        self._reserve_selection(slots, command + cells)
        self._commands[id(selection)] = command
        self._commands_made += cells
        starts = selection.particles.cloud_starts
        clouds = np.asarray(selection.clouds, dtype=np.int64)
        counts = starts[clouds + 1] - starts[clouds]
        # the shader's Range: start, before, near, far, cell, three unused
        ranges = np.zeros((len(clouds), _RANGE_UINTS), dtype=np.uint32)
        ranges[:, 0] = starts[clouds]
        ranges[:, 1] = np.cumsum(counts) - counts
        everything = [(-1.0, np.inf)] * len(clouds)
        depth = np.array(everything if selection.depth_ranges is None else selection.depth_ranges, dtype=np.float64)
        ranges[:, 2:4].view(np.float32)[:] = np.clip(depth, -1.0, np.finfo(np.float32).max)
        ranges[:, 4] = 0 if selection.cells is None else selection.cells
        _store(self._ranges_buffer, ranges, GL.GL_STREAM_DRAW)
        # each cell's count is the GPU's to add to; its quads start at its first slot
        records = np.zeros((cells, _COMMAND_UINTS), dtype=np.uint32)
        records[:, 1], records[:, 3] = 1, 4 * (first + selection.cell_slots()[0])
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._command_buffer)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, records[0].nbytes * command, records.nbytes, records)
        _bind_storage(
            (_SELECT_PARTICLES, self._particle_buffer),
            (_SELECT_FORMATION, self._formation_buffer),
            (_SELECT_BITS, self._drawn_bits_buffer),
            (_SELECT_RANGES, self._ranges_buffer),
            (_SELECT_KEYS, self._keys_buffer),
            (_SELECT_VALUES, self._values_buffer),
            (_SELECT_COMMAND, self._command_buffer),
        )
        GL.glUseProgram(program)
        GL.glUniform1ui(uniforms["count"], slots)
        GL.glUniform1ui(uniforms["range_count"], len(clouds))
        GL.glUniform1ui(uniforms["command_at"], _COMMAND_UINTS * command)
        eye = np.asarray(selection.eye, dtype=np.float64)
        set_vec3_at(uniforms["eye"], eye)
        GL.glUniform1i(uniforms["cull_to_frustum"], selection.frustum is not None)
        if selection.frustum is not None:
            planes = np.array(selection.frustum, dtype=np.float64)
            planes[:, 3] += planes[:, :3] @ eye  # relative to the eye: float32 keeps their precision there
            GL.glUniform4fv(uniforms["planes"], 6, np.ascontiguousarray(planes, dtype=np.float32))
        dispatch(-(-slots // _SELECT_GROUP))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        sort.sort(self._keys_buffer, self._values_buffer, slots)
        if cells > 1:
            self._resolve(slots, len(clouds), cell_keys=True)
            sort.sort(self._keys_buffer, self._values_buffer, slots, key_bits=key_bits_for(cells - 1))
        self._resolve(slots, len(clouds), cell_keys=False, first=first)

    def _resolve(self, slots: int, ranges: int, cell_keys: bool, first: int = 0) -> None:
        """After a sort of a selection's slots: key each by its cell (`cell_keys`), or write each one's particle
        into the order from slot `first` on (splat_select.comp.glsl's RESOLVE)."""
        program, uniforms = self._selecting[3:]
        _bind_storage(
            (_SELECT_RANGES, self._ranges_buffer),
            (_SELECT_KEYS, self._keys_buffer),
            (_SELECT_VALUES, self._values_buffer),
            (_SELECT_ORDER, self._order_buffer),
        )
        GL.glUseProgram(program)
        GL.glUniform1ui(uniforms["count"], slots)
        GL.glUniform1ui(uniforms["range_count"], ranges)
        GL.glUniform1i(uniforms["cell_keys"], cell_keys)
        GL.glUniform1ui(uniforms["first"], first)
        dispatch(-(-slots // _SELECT_GROUP))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)

    def _reserve_selection(self, slots: int, commands: int) -> None:
        """Room for choosing `slots` particles and for `commands` indirect commands, keeping those made."""
        if slots > self._keys_capacity:
            self._keys_capacity = max(slots, 2 * self._keys_capacity)
            reallocate_storage((self._keys_buffer, self._values_buffer), 4 * self._keys_capacity)
        if commands > self._command_capacity:
            capacity, size = max(commands, 2 * self._command_capacity, 16), 4 * _COMMAND_UINTS
            scratch = GL.glGenBuffers(1)
            if self._command_capacity:
                _copy_buffer(self._command_buffer, scratch, size * self._command_capacity, allocate=True)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._command_buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, size * capacity, None, GL.GL_DYNAMIC_COPY)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
            if self._command_capacity:
                _copy_buffer(scratch, self._command_buffer, size * self._command_capacity, allocate=False)
            GL.glDeleteBuffers(1, [scratch])
            self._command_capacity = capacity

    def _make_resident(self, particles: ParticleBuffer) -> None:
        """Upload the particles' shading terms, styles and unlocked facings when the particles change."""
        if particles is not self._resident:
            _store(self._particle_buffer, _particle_records(particles))
            _store(self._cloud_buffer, _cloud_records(particles.styles))
            _store(
                self._facing_buffer,
                np.tile(np.array(_UNLOCKED, dtype=np.float32), (max(len(particles.radii), 1), 1)),
                GL.GL_DYNAMIC_DRAW,
            )
            self._plain = plain_splats(particles.styles)
            # per cloud, whether all its particles are plain: asked each frame, of hundreds of clouds on a field
            not_plain = np.concatenate([[0], np.cumsum(~self._plain)])
            self._cloud_plain = not_plain[particles.cloud_starts[1:]] == not_plain[particles.cloud_starts[:-1]]
            self._sprites = particles.styles.sprite_index >= 0
            if self._atlas is None and np.any(particles.styles.sprite_index >= 0):
                self._atlas = _atlas_texture()
            _store(self._formation_buffer, np.ones(max(len(particles.radii), 1), dtype=np.float32))
            # Yusov's eye pass's profile rows; one float where there are none (no empty buffer is bound)
            rows = np.zeros(0) if particles.profiles is None else particles.profiles.profiles.ravel()
            _store(self._profile_buffer, (rows if rows.size else np.zeros(1)).astype(np.float32))
            per_cloud = [(s.facing != FACING_SPLAT) | (s.artist is not None) << 1 for s in particles.styles.clouds]
            self._feature_bits = np.array(per_cloud + [0], dtype=np.uint8)[particles.styles.cloud_index]
            self._profiled = particles.profiles is not None
            self._cloud_feature_bits = np.array(per_cloud + [0], dtype=np.uint8)
            self._cloud_sprites = np.array(
                [np.any(self._sprites[a:b]) for a, b in zip(particles.cloud_starts[:-1], particles.cloud_starts[1:])]
                + [False]
            )
            _store(self._drawn_bits_buffer, np.append(particles.drawn_bits, np.uint32(0)))
            self._resident, self._formation_time = particles, None

    def _features(self, batch: SplatBatch | SplatSelection) -> tuple[bool, bool, bool, bool]:
        """The shader features (`_SHADE_FEATURES`) `batch`'s particles need."""
        self._make_resident(batch.particles)
        if isinstance(batch, SplatSelection):
            bits = int(np.bitwise_or.reduce(self._cloud_feature_bits[list(batch.clouds)]))
        else:
            bits = int(np.bitwise_or.reduce(self._feature_bits[batch.order])) if len(batch) else 0
        return bool(bits & 1), bool(bits & 2), self._profiled, batch.through_air and self.air is not None

    def _shade_program(self, features: tuple[bool, bool, bool, bool]) -> tuple[int, dict]:
        """The compute shader variant with `features`, its light uniforms those of the resident particles; and
        its uniforms' locations."""
        if features not in self._shade_programs:
            program = build_compute_program(
                "splat_shade",
                {"MAX_LIGHTS": MAX_LIGHTS, "FADE_START_RADII": FADE_START_RADII, "FADE_END_RADII": FADE_END_RADII}
                | {name: 1 for name, on in zip(_SHADE_FEATURES, features) if on},
            )
            self._shade_programs[features] = [
                program,
                uniform_locations(program, ("first", "slot_count", "batch_count")),
                None,
            ]
        held = self._shade_programs[features]
        if held[2] is not self._resident:
            _set_light_uniforms(held[0], self._resident)
            held[2] = self._resident
        return held[0], held[1]

    def _hold_formation(self, particles: ParticleBuffer, time_s: float | None) -> None:
        """Upload the opacity factors (formation at `time_s`, blend weights) when they differ from those held."""
        factors = particles.opacity_factors(time_s)
        # what the buffer's factors are for: the time and the weights; None: all 1
        held = None if factors is None else (time_s, particles.weights_serial)
        if held != self._formation_time:
            _store(
                self._formation_buffer,
                (np.ones(max(len(particles.radii), 1)) if factors is None else factors).astype(np.float32),
            )
            self._formation_time = held

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        for program in (*self._programs.values(), *(held[0] for held in self._shade_programs.values())):
            GL.glDeleteProgram(program)
        for program, _ in self._cell_programs.values():
            GL.glDeleteProgram(program)
        if self._selecting is not None:
            GL.glDeleteProgram(self._selecting[0])
            GL.glDeleteProgram(self._selecting[3])
            self._selecting[2].close()
        if self._atlas is not None:
            GL.glDeleteTextures([self._atlas])
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))
        GL.glDeleteBuffers(len(self._selection_buffers), list(self._selection_buffers))
        GL.glDeleteVertexArrays(1, [self._vertex_array])
        self._resident = None


def _particle_records(particles: ParticleBuffer) -> np.ndarray:
    """The shader's `Particle` array (n, _PARTICLE_FLOATS) float32: the view-independent terms of `seen_from`."""
    lights = len(particles.light_directions)
    if lights > MAX_LIGHTS:  # the scene loader and the editor refuse these first (cloudcore.limits)
        raise ValueError(f"at most {MAX_LIGHTS} lights can shine on clouds at once, the scene has {lights}")
    records = np.zeros((max(len(particles.radii), 1), _PARTICLE_FLOATS), dtype=np.float32)
    n = len(particles.radii)
    records[:n, 0:3] = particles.centres
    records[:n, 3] = particles.radii
    records[:n, 4:7] = particles.scattering[:, None] * particles.tint
    records[:n, 7] = particles.alpha
    records[:n, 8:11] = particles.ambient * particles.ambient_weight[:, None] * particles.tint
    styles = particles.styles
    records[:n, 12:15] = styles.group_centres
    records[:n, 15] = styles.cloud_index
    records[:n, 16] = styles.sprite_index
    records[:n, 17] = styles.rotation
    records[:n, 18] = -1.0 if particles.profiles is None else particles.profiles.rows
    records[:n, 20 : 20 + lights] = particles.incident
    return records


def _cloud_records(styles: ParticleStyles) -> np.ndarray:
    """The shader's `CloudStyle` array (clouds, _CLOUD_FLOATS) float32."""
    records = np.zeros((max(len(styles.clouds), 1), _CLOUD_FLOATS), dtype=np.float32)
    for record, style in zip(records, styles.clouds):
        record[25:27] = style.bottom_y, style.top_y
        record[31] = style.facing
        if style.artist is not None:
            heights = style.artist["level_heights"]
            record[0:20] = style.artist["level_colours"].ravel()
            record[20:25] = heights
            record[27] = 1.0
            record[28:31] = style.artist["directional_colour"]
            record[32:35] = style.artist["directional_range"]
            record[36:39] = style.artist["sun_direction"]
    return records


def _atlas_texture() -> int:
    """The sprite atlas, mipmapped down to the level its cells' empty margins keep apart."""
    pixels = np.ascontiguousarray(load_atlas())
    texture = GL.glGenTextures(1)
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, ATLAS_MAX_MIP_LEVEL)
    GL.glTexStorage2D(GL.GL_TEXTURE_2D, ATLAS_MAX_MIP_LEVEL + 1, GL.GL_RGBA8, pixels.shape[1], pixels.shape[0])
    GL.glTexSubImage2D(GL.GL_TEXTURE_2D, 0, 0, 0, pixels.shape[1], pixels.shape[0], GL.GL_RGBA, GL.GL_FLOAT, pixels)
    GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
    return texture


def _set_light_uniforms(program: int, particles: ParticleBuffer) -> None:
    GL.glUseProgram(program)
    # Yusov's eye pass: samples per profile row (the rows are in the profiles buffer)
    samples = 0 if particles.profiles is None else particles.profiles.profiles.shape[2]
    GL.glUniform1i(GL.glGetUniformLocation(program, "profile_samples"), samples)
    lights = len(particles.light_directions)
    GL.glUniform1i(GL.glGetUniformLocation(program, "light_count"), lights)
    if lights:
        GL.glUniform3fv(
            GL.glGetUniformLocation(program, "light_direction"),
            lights,
            np.ascontiguousarray(particles.light_directions, dtype=np.float32),
        )
        GL.glUniform3fv(
            GL.glGetUniformLocation(program, "light_radiance"),
            lights,
            np.ascontiguousarray(particles.light_radiance, dtype=np.float32),
        )
    GL.glUniform1i(GL.glGetUniformLocation(program, "phase_kind"), PHASE_NAMES.index(particles.phase))
    GL.glUniform1f(GL.glGetUniformLocation(program, "g"), float(particles.g))


#: what a draw after shading waits for: the instances (and a selection's indirect command)
_SHADED_BARRIERS = GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_COMMAND_BARRIER_BIT


def _rotation(view: np.ndarray) -> np.ndarray:
    """The view matrix without its translation: corners come relative to the batch's eye, the view's own."""
    rotation = np.array(view, dtype=np.float64)
    rotation[:3, 3] = 0.0
    return rotation


def reallocate_storage(buffers, size: int) -> None:
    """Give each storage buffer of `buffers` `size` bytes, its contents undefined (scratch space that grows)."""
    for buffer in buffers:
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, size, None, GL.GL_DYNAMIC_COPY)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)


def _bind_storage(*bindings) -> None:
    """Bind each (binding point, buffer) pair as a shader storage buffer."""
    for binding, buffer in bindings:
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, binding, buffer)


def _copy_buffer(source: int, destination: int, size: int, allocate: bool) -> None:
    """Copy the first `size` bytes of buffer `source` into `destination` (first given that size: `allocate`)."""
    GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, source)
    GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, destination)
    if allocate:
        GL.glBufferData(GL.GL_COPY_WRITE_BUFFER, size, None, GL.GL_STREAM_COPY)
    GL.glCopyBufferSubData(GL.GL_COPY_READ_BUFFER, GL.GL_COPY_WRITE_BUFFER, 0, 0, size)
    GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, 0)
    GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, 0)


def _store(buffer: int, data: np.ndarray, usage=GL.GL_STATIC_DRAW) -> None:
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
    GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, data.nbytes, np.ascontiguousarray(data), usage)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)


def _viewport_groups(cells, viewports, scissors):
    """(start, stop) of each run of at most MAX_VIEWPORTS `cells`, their `viewports` and `scissors` (x, y,
    width, height) set as the indexed viewports and scissors of one multi-draw."""
    for start in range(0, len(cells), _MAX_VIEWPORTS):
        stop = min(start + _MAX_VIEWPORTS, len(cells))
        GL.glViewportArrayv(0, stop - start, np.array(viewports[start:stop], dtype=np.float32))
        GL.glScissorArrayv(0, stop - start, np.array(scissors[start:stop], dtype=np.int32))
        yield start, stop
