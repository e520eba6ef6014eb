"""The GPU's selection and order of a draw's splats: `splat_batch`'s choice made on the GPU, and its count.

For a `SplatSelection`, `splat_select.comp.glsl` keys each particle of its clouds the draw keeps by its
distance from the eye (the others sort last), `cloudcore.gl.depth_sort` sorts the keys, and the RESOLVE pass
writes the kept particles into the draw's slots of the order, far to near, counting them into an indirect
draw command of quads: the CPU's work for the draw no longer grows with its particles.  A selection of many
cells (a frame's impostor regenerations) is sorted by distance then by cell, one command a cell.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.depth_sort import GpuDepthSort, key_bits_for
from cloudcore.gl.programs import build_compute_program, dispatch, set_vec3_at, uniform_locations
from cloudcore.gl.splat_residency import PARTICLE_FLOATS, ResidentParticles
from cloudcore.gl.storage import bind_storage, copy_buffer, reallocate_storage, store
from cloudcore.maths.splat_kernel import SPLAT_REACH
from cloudcore.particles.batch import SplatSelection
from cloudcore.particles.buffer import FADE_START_RADII

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
#: the compute shader's local_size_x
_SELECT_GROUP = 64
#: uints of a DrawElementsIndirectCommand: count, instance count, first index, base vertex, base instance
COMMAND_UINTS = 5


class GpuSplatOrder:
    """Chooses and sorts selections' particles on the GPU, into the order the shading reads, and keeps their
    indirect draw commands and which of them were drawn."""

    def __init__(self, resident: ResidentParticles):
        self._resident = resident
        #: made when a selection first needs it: (splat_select's program, its uniforms' locations, the sort,
        #: the RESOLVE program, its uniforms' locations)
        self._selecting: tuple | None = None
        (
            self._ranges_buffer,
            self._keys_buffer,
            self._values_buffer,
            self.command_buffer,
        ) = self._buffers = GL.glGenBuffers(4)
        self._keys_capacity = self._command_capacity = 0
        #: the selections chosen since `begin_pass`: id -> their first indirect command's index (one a cell); the
        #: commands made since `take_selected`, which begins them again from 0
        self._commands: dict[int, int] = {}
        self._commands_made = 0
        #: commands drawn (not counting fragments) since `take_selected`: into the target, into cells
        self._drawn_commands: list[int] = []
        self._drawn_cell_commands: list[int] = []

    def begin_pass(self) -> None:
        """Forget the selections chosen before: a pass shades (and chooses) its own."""
        self._commands = {}

    def command(self, selection: SplatSelection) -> int:
        """The index of the selection's first indirect command (one a cell)."""
        return self._commands[id(selection)]

    def drawn(self, selection: SplatSelection, cells: bool = False) -> None:
        """Count a selection's particles as drawn (`take_selected`), into the target or (`cells`) into cells."""
        command = self._commands[id(selection)]
        if cells:
            self._drawn_cell_commands.extend(range(command, command + selection.cell_count))
        else:
            self._drawn_commands.append(command)

    def take_selected(self) -> tuple[int, int]:
        """(the particles that the selections drawn into targets since the last call chose, those drawn into
        cells), read from their commands (after the draws finished, this waits for nothing); the commands
        are made from the first again."""
        drawn = self._drawn_commands + self._drawn_cell_commands
        counts = self.command_counts(max(drawn) + 1) if drawn else np.zeros(0, dtype=np.int64)
        taken = tuple(int(counts[commands].sum()) for commands in (self._drawn_commands, self._drawn_cell_commands))
        self._drawn_commands, self._drawn_cell_commands, self._commands_made = [], [], 0
        return taken

    def command_counts(self, commands: int) -> np.ndarray:
        """The particles the first `commands` indirect commands count (reading them waits for the GPU)."""
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, self.command_buffer)
        size = 4 * COMMAND_UINTS * commands
        records = np.frombuffer(GL.glGetBufferSubData(GL.GL_COPY_READ_BUFFER, 0, size), dtype=np.uint32)
        GL.glBindBuffer(GL.GL_COPY_READ_BUFFER, 0)
        return records.reshape(-1, COMMAND_UINTS)[:, 0].astype(np.int64) // 6

    def select(self, selection: SplatSelection, first: int, order_buffer: int) -> None:
        """Choose and sort `selection`'s particles on the GPU into the order (`order_buffer`) from slot `first`
        on, each cell's from its first slot on (`SplatSelection.cell_slots`), the chosen first, far to near, and
        count them into a new indirect command of quads a cell."""
        if self._selecting is None:
            defines = {
                "PARTICLE_FLOATS": PARTICLE_FLOATS,
                "FADE_START_RADII": FADE_START_RADII,
                "SPLAT_REACH": SPLAT_REACH,
                "COMMAND_UINTS": COMMAND_UINTS,
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
        store(self._ranges_buffer, ranges, GL.GL_STREAM_DRAW)
        # each cell's count is the GPU's to add to; its quads start at its first slot
        records = np.zeros((cells, COMMAND_UINTS), dtype=np.uint32)
        records[:, 1], records[:, 3] = 1, 4 * (first + selection.cell_slots()[0])
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self.command_buffer)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, records[0].nbytes * command, records.nbytes, records)
        bind_storage(
            (_SELECT_PARTICLES, self._resident.particle_buffer),
            (_SELECT_FORMATION, self._resident.formation_buffer),
            (_SELECT_BITS, self._resident.drawn_bits_buffer),
            (_SELECT_RANGES, self._ranges_buffer),
            (_SELECT_KEYS, self._keys_buffer),
            (_SELECT_VALUES, self._values_buffer),
            (_SELECT_COMMAND, self.command_buffer),
        )
        GL.glUseProgram(program)
        GL.glUniform1ui(uniforms["count"], slots)
        GL.glUniform1ui(uniforms["range_count"], len(clouds))
        GL.glUniform1ui(uniforms["command_at"], COMMAND_UINTS * command)
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
            self._resolve(slots, len(clouds), order_buffer, cell_keys=True)
            sort.sort(self._keys_buffer, self._values_buffer, slots, key_bits=key_bits_for(cells - 1))
        self._resolve(slots, len(clouds), order_buffer, cell_keys=False, first=first)

    def _resolve(self, slots: int, ranges: int, order_buffer: int, cell_keys: bool, first: int = 0) -> None:
        """After a sort of a selection's slots: key each by its cell (`cell_keys`), or write each one's particle
        into the order from slot `first` on (splat_select.comp.glsl's RESOLVE)."""
        program, uniforms = self._selecting[3:]
        bind_storage(
            (_SELECT_RANGES, self._ranges_buffer),
            (_SELECT_KEYS, self._keys_buffer),
            (_SELECT_VALUES, self._values_buffer),
            (_SELECT_ORDER, order_buffer),
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
            capacity, size = max(commands, 2 * self._command_capacity, 16), 4 * COMMAND_UINTS
            scratch = GL.glGenBuffers(1)
            if self._command_capacity:
                copy_buffer(self.command_buffer, scratch, size * self._command_capacity, allocate=True)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self.command_buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, size * capacity, None, GL.GL_DYNAMIC_COPY)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
            if self._command_capacity:
                copy_buffer(scratch, self.command_buffer, size * self._command_capacity, allocate=False)
            GL.glDeleteBuffers(1, [scratch])
            self._command_capacity = capacity

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        if self._selecting is not None:
            GL.glDeleteProgram(self._selecting[0])
            GL.glDeleteProgram(self._selecting[3])
            self._selecting[2].close()
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))
