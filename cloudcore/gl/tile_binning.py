"""A draw's splats binned into screen tiles on the GPU, for compositing them by compute (as volumes, or plain
splats chosen on the GPU as the raster blends them).

On the H200 (docs/performance.md, "On a GPU (NVIDIA H200)") the raster of full 3D's splats took 16.5 of
the frame's 17.4 GPU milliseconds at 640x480, and the tiled compute pass of volume-aware blending did
more per splat in half the raster's time: such chips keep little of their area for the raster.  The
compute pass needs each tile's splats far to near, which `cloudcore.light.volume_blending.screen_tiles`
makes in numpy (79 ms of CPU a frame there).  Here the GPU makes them from the draw's shaded instances
(`shaders/tile_bin.comp.glsl`): each kept splat counts the tiles its disc's image touches, the counts'
prefix sum over the slots (`cloudcore.gl.prefix_sum`) says where each splat's pairs go, one (slot, tile)
pair a tile is written there, in the draw's far-to-near order, and one stable radix sort by tile
(`cloudcore.gl.depth_sort`) leaves each tile's run far to near; the runs' starts are the tiles'
`starts`, as `ScreenTiles` has them.

How many pairs a draw makes is known only once the GPU has counted them, and a draw's buffers and the sort's
work must be sized before.  Reading the count back made the CPU wait, mid-frame, for everything the GPU had
queued before it: on the H200 that cost the compute pass more CPU a frame than auto mode's small full-3D draws
gain by it (docs/performance.md, "Compositing by compute").  So the count stays on the GPU: the buffers get `room`
for `ROOM_FACTOR` times the most pairs a draw had in the frame before (at least `MIN_ROOM`), the shaders take
the lesser of the count and the room, and the counts are read once the frame has been waited for
(`GpuTileBinning.settle`).  A draw with more pairs than its room has lost its nearest splats: `settle` says so,
and the frame is drawn again, each draw's count read back first as before (`cloudcore.gl.frame`).  That first
frame, and a frame whose draw had more than `MAX_PAIRS` (which the raster then draws), count on the CPU's side,
and so does a software GL (`counts_stay_on_gpu`).

The pairs were first written where an atomic counter handed out places, in no order, and sorted by slot
before the sort by tile: that sort by slot (24 bits for the default scene's 82,000 slots) took 44% of the
pass on llvmpipe inside a cloud (456 of 1048 ms at 640x480), where the prefix sum takes a few.  The tiles
were those of the quad's square: its corners, outside the disc where the kernel is 0, held a quarter of the
pairs, and splats wholly behind the near plane (kept by the frustum, clipped by the raster) the whole screen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from OpenGL import GL

from cloudcore.gl.depth_sort import GpuDepthSort, key_bits_for
from cloudcore.gl.measured_way import software_rasterizer
from cloudcore.gl.prefix_sum import GpuPrefixSum
from cloudcore.gl.programs import (
    build_compute_program,
    dispatch,
    gl_renderer,
    max_dispatch_groups,
    set_matrix_at,
    uniform_locations,
)
from cloudcore.gl.splat_shading import INSTANCE_BYTES
from cloudcore.gl.storage import reallocate_storage
from cloudcore.light.volume_blending import TILE_PIXELS
from cloudcore.world.camera import NEAR_PLANE_M

#: the storage bindings of tile_bin.comp.glsl (instances and command as the splat pass binds them)
_INSTANCES, _COMMAND, _TOTALS, _PAIR_SLOTS, _PAIR_TILES, _TILE_STARTS, _PAIR_STARTS = 3, 6, 9, 10, 11, 12, 13
#: and of shaders/binned_splats.glsl, which volume_blend.comp.glsl reads at the same bindings: the occupied
#: tiles and the splats' discs
OCCUPIED_BINDING, DISCS_BINDING = 8, 14
#: the occupied buffer's header: a DispatchIndirectCommand (x, y, z groups) and the tiles' count
_OCCUPIED_HEADER = np.array([0, 1, 1, 0], dtype=np.uint32)
#: a disc's bytes: its image, colour, centre and radius squared (three vec4)
_DISC_BYTES = 48
#: the command's index that says every slot is kept (tile_bin.comp.glsl's ALL_SLOTS)
_ALL_SLOTS = 0xFFFFFFFF
_GROUP = 64
#: pairs past which a draw is left to the raster: 16 bytes each with the sorts' scratch, 512 MiB (at 1600x1200
#: inside a cloud of the default scene, 7.1 million; a 4K screen there, about 30)
MAX_PAIRS = 1 << 25
#: a draw's room over the most pairs a draw had the frame before: along the default flythrough in full 3D a
#: frame's pairs grew by at most 1.42 times the frame before's (99% of frames by less than 1.005)
ROOM_FACTOR = 1.5
#: the least room: auto mode's full-3D draws come and go, from none to 82,459 pairs between two frames along the
#: flythrough; with this floor 1 frame of its 901 was drawn again (2^16: 2), and a room past the pairs costs a
#: GPU only the sort's and the starts' work groups that find nothing to do
MIN_ROOM = 1 << 17
#: the draws a frame bins with their count left on the GPU; past them, a draw's count is read back at once
_TOTALS_HELD = 64
_UNIFORMS = (
    *("slots", "count_at", "view_rotation", "projection", "size", "tiles_across", "tiles_up", "near"),
    *("total_at", "room", "max_groups"),
)


def counts_stay_on_gpu() -> bool:
    """Whether draws' pair counts stay on the GPU (the module's docstring).  A software GL runs each compute
    dispatch as it is issued, so there the count is ready to read without waiting, and a room past the pairs
    costs it what the GPU skips: the default view's binning took 62 against 48 ms on llvmpipe."""
    return not software_rasterizer(gl_renderer())


@dataclass(frozen=True)
class BinnedTiles:
    """A draw's splats by screen tile, in GPU buffers: tile t's are the slots `entries[starts[t]:starts[t + 1]]`
    (from the draw's first), far to near; tiles counted from the lower left, `TILE_PIXELS` square."""

    size: tuple[int, int]
    across: int
    up: int
    starts: int  # buffer of across * up + 1 uints
    entries: int  # buffer of `pairs` uints
    pairs: int | None  # None: counted on the GPU, at most `room` (`GpuTileBinning.read` reads it)
    room: int
    total: tuple[int, int]  # the buffer and uint index of the pairs' count
    discs: int  # buffer of what the compositing reads of each slot's splat (tile_bin.comp.glsl's Disc)
    #: buffer of the tiles with splats, in no order, after the indirect dispatch that composites them (one
    #: group a tile: `_OCCUPIED_HEADER`)
    occupied: int


class GpuTileBinning:
    """The binning's programs and buffers; `bin` bins one draw, `settle` ends a frame's."""

    def __init__(self):
        defines = {"TILE_PIXELS": TILE_PIXELS}
        self._programs = {
            stage: build_compute_program("tile_bin", defines | {stage: 1}) for stage in ("COUNT", "EMIT", "STARTS")
        }
        self._uniforms = {stage: uniform_locations(program, _UNIFORMS) for stage, program in self._programs.items()}
        self._buffers = GL.glGenBuffers(8)
        self._totals, self._read_total = self._buffers[:2]
        self._slots, self._tiles, self._starts, self._pair_starts, self._discs, self._occupied = self._buffers[2:]
        reallocate_storage((self._totals,), 4 * _TOTALS_HELD)
        reallocate_storage((self._read_total,), 4)
        self._pair_capacity = self._tile_capacity = self._slot_capacity = 0
        #: pairs a draw's buffers hold while the counts stay on the GPU; None: read each draw's count back
        self._room: int | None = None
        #: this frame's draws: (index in `_totals`, the room they had), or (None, the count read back)
        self._binned: list[tuple[int | None, int]] = []
        self._sort = GpuDepthSort()
        self._prefix_sum = GpuPrefixSum()

    def bin(
        self,
        instances: tuple[int, int, int],
        count_at: tuple[int, int] | None,
        view: np.ndarray,
        projection: np.ndarray,
        size: tuple[int, int],
    ) -> BinnedTiles | None:
        """Bin a draw's shaded splats (`instances`: their buffer, first slot, slots; `count_at`: the buffer
        and uint index of its indirect command's count, six a kept splat, or None where every slot is kept)
        for a screen of `size` pixels seen with `view` and `projection`.  Counted on the GPU (the module's
        docstring), `pairs` is None; counted here, 0 when no splat touches the screen, and None returned
        when there would be more than `MAX_PAIRS` (the raster draws those)."""
        buffer, first, slots = instances
        across, up = -(-size[0] // TILE_PIXELS), -(-size[1] // TILE_PIXELS)
        on_gpu = self._room is not None and len(self._binned) < _TOTALS_HELD
        total = (self._totals, len(self._binned)) if on_gpu else (self._read_total, 0)

        def binned(pairs: int | None, room: int) -> BinnedTiles:
            return BinnedTiles(
                tuple(size), across, up, self._starts, self._slots, pairs, room, total, self._discs, self._occupied
            )

        if not slots:
            return binned(0, 0)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, total[0])
        # cleared by the GPU in its queue: a copy from the CPU into a buffer the frame's draws before still use
        # may make a driver wait for them
        GL.glClearBufferSubData(
            GL.GL_SHADER_STORAGE_BUFFER, GL.GL_R32UI, 4 * total[1], 4, GL.GL_RED_INTEGER, GL.GL_UNSIGNED_INT, None
        )
        if slots > self._slot_capacity:
            self._slot_capacity = max(slots, 2 * self._slot_capacity)
            reallocate_storage((self._pair_starts,), 4 * self._slot_capacity)
            reallocate_storage((self._discs,), _DISC_BYTES * self._slot_capacity)
        GL.glBindBufferRange(
            GL.GL_SHADER_STORAGE_BUFFER, _INSTANCES, buffer, first * INSTANCE_BYTES, slots * INSTANCE_BYTES
        )
        # without a command, the totals stand in for it: a shader's storage blocks must all be bound
        count_at = (total[0], _ALL_SLOTS) if count_at is None else count_at
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _COMMAND, count_at[0])
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TOTALS, total[0])
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_STARTS, self._pair_starts)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, DISCS_BINDING, self._discs)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        shared = (count_at[1], view, projection, size, (across, up), total[1])  # what the stages share
        self._dispatch("COUNT", slots, *shared, room=0)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        self._prefix_sum.scan(self._pair_starts, slots)  # issued before any read-back waits: the GPU goes on
        if on_gpu:  # past MAX_PAIRS the raster draws: a draw with more overflows its room, then counted here
            pairs, room = None, min(self._room, MAX_PAIRS)
            self._binned.append((total[1], room))
        else:
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, total[0])
            pairs = room = int(np.frombuffer(GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, 4), np.uint32)[0])
            self._binned.append((None, pairs))
            if not pairs or pairs > MAX_PAIRS:
                return None if pairs else binned(0, 0)
        self._reserve(room, across * up + 1)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_SLOTS, self._slots)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_TILES, self._tiles)
        self._dispatch("EMIT", slots, *shared, room=room)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        # the pairs in the draw's order (far to near), sorted stably by tile: each tile's run keeps that order
        key_bits = key_bits_for(across * up - 1)
        self._sort.sort(self._tiles, self._slots, room, key_bits=key_bits, count_at=total if on_gpu else None)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TOTALS, total[0])
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_TILES, self._tiles)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TILE_STARTS, self._starts)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._occupied)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, _OCCUPIED_HEADER.nbytes, _OCCUPIED_HEADER)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, OCCUPIED_BINDING, self._occupied)
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        program, uniforms = self._programs["STARTS"], self._uniforms["STARTS"]
        GL.glUseProgram(program)
        GL.glUniform1ui(uniforms["total_at"], total[1])
        GL.glUniform1ui(uniforms["room"], room)
        GL.glUniform1ui(uniforms["max_groups"], max_dispatch_groups())
        GL.glUniform1i(uniforms["tiles_across"], across)
        GL.glUniform1i(uniforms["tiles_up"], up)
        dispatch(-(-room // _GROUP))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_COMMAND_BARRIER_BIT)
        return binned(pairs, room)

    def settle(self) -> bool:
        """End a frame's binning, once the frame has been waited for (reading its counts then waits for
        nothing): whether a draw counted on the GPU had more pairs than its room, so that its nearest splats
        are missing and the frame must be drawn again.  The next frames' room follows this one's largest
        draw; past `MAX_PAIRS`, and for the frame drawn again, each draw's count is read back."""
        binned, self._binned = self._binned, []
        if not binned:
            return False
        held = [index for index, _ in binned if index is not None]
        totals = self._read(self._totals, 0, max(held) + 1) if held else np.zeros(0, np.uint32)
        counts = [int(totals[index]) if index is not None else room for index, room in binned]
        overflowed = any(index is not None and count > room for (index, room), count in zip(binned, counts))
        most = max(counts)
        on_gpu = counts_stay_on_gpu() and not overflowed and most <= MAX_PAIRS
        self._room = max(MIN_ROOM, int(np.ceil(ROOM_FACTOR * most))) if on_gpu else None
        return overflowed

    def read(self, binned: BinnedTiles) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(starts, entries, occupied tiles, their dispatch's groups) of `binned` read back, as `ScreenTiles` holds
        the first three (the tests compare them)."""
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        pairs = binned.pairs
        if pairs is None:
            pairs = min(int(self._read(binned.total[0], binned.total[1], 1)[0]), binned.room)
        header = self._read(binned.occupied, 0, len(_OCCUPIED_HEADER))
        starts = self._read(binned.starts, 0, binned.across * binned.up + 1)
        occupied = self._read(binned.occupied, len(_OCCUPIED_HEADER), int(header[3]))
        return starts, self._read(binned.entries, 0, pairs), occupied, header[:3]

    @staticmethod
    def _read(buffer: int, first: int, count: int) -> np.ndarray:
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
        data = GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 4 * first, 4 * count) if count else b""
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        return np.frombuffer(data, np.uint32).copy()

    def _dispatch(self, stage: str, slots: int, count_at: int, view, projection, size, tiles, total_at, room) -> None:
        program, uniforms = self._programs[stage], self._uniforms[stage]
        GL.glUseProgram(program)
        GL.glUniform1ui(uniforms["slots"], slots)
        GL.glUniform1ui(uniforms["count_at"], count_at)
        rotation = np.eye(4)
        rotation[:3, :3] = view[:3, :3]  # the instances' corners are relative to the eye
        set_matrix_at(uniforms["view_rotation"], rotation)
        set_matrix_at(uniforms["projection"], projection)
        GL.glUniform2i(uniforms["size"], *size)
        GL.glUniform1i(uniforms["tiles_across"], tiles[0])
        GL.glUniform1i(uniforms["tiles_up"], tiles[1])
        GL.glUniform1f(uniforms["near"], NEAR_PLANE_M)
        GL.glUniform1ui(uniforms["total_at"], total_at)
        GL.glUniform1ui(uniforms["room"], room)
        dispatch(-(-slots // _GROUP))

    def _reserve(self, pairs: int, starts: int) -> None:
        """Room for `pairs` pairs and `starts` tile starts, growing geometrically."""
        if pairs > self._pair_capacity:
            self._pair_capacity = max(pairs, 2 * self._pair_capacity)
            reallocate_storage((self._slots, self._tiles), 4 * self._pair_capacity)
        if starts > self._tile_capacity:
            self._tile_capacity = starts
            reallocate_storage((self._starts,), 4 * starts)
            reallocate_storage((self._occupied,), _OCCUPIED_HEADER.nbytes + 4 * starts)

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        for program in self._programs.values():
            GL.glDeleteProgram(program)
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))
        self._sort.close()
        self._prefix_sum.close()
