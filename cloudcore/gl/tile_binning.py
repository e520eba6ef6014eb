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
`starts`, as `ScreenTiles` has them.  The CPU reads back one number, the pairs' count, to size the sort.

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

from cloudcore.camera import NEAR_PLANE_M
from cloudcore.gl.depth_sort import GpuDepthSort, key_bits_for
from cloudcore.gl.prefix_sum import GpuPrefixSum
from cloudcore.gl.programs import build_compute_program, dispatch, max_dispatch_groups, set_matrix_at, uniform_locations
from cloudcore.gl.splats import INSTANCE_BYTES, reallocate_storage
from cloudcore.light.volume_blending import TILE_PIXELS

#: the storage bindings of tile_bin.comp.glsl (instances and command as the splat pass binds them)
_INSTANCES, _COMMAND, _COUNTER, _PAIR_SLOTS, _PAIR_TILES, _TILE_STARTS, _PAIR_STARTS = 3, 6, 9, 10, 11, 12, 13
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
_UNIFORMS = (
    *("slots", "count_at", "view_rotation", "projection", "size", "tiles_across", "tiles_up", "near"),
    *("pairs", "max_groups"),
)


@dataclass(frozen=True)
class BinnedTiles:
    """A draw's splats by screen tile, in GPU buffers: tile t's are the slots `entries[starts[t]:starts[t + 1]]`
    (from the draw's first), far to near; tiles counted from the lower left, `TILE_PIXELS` square."""

    size: tuple[int, int]
    across: int
    up: int
    starts: int  # buffer of across * up + 1 uints
    entries: int  # buffer of `pairs` uints
    pairs: int
    discs: int  # buffer of what the compositing reads of each slot's splat (tile_bin.comp.glsl's Disc)
    #: buffer of the tiles with splats, in no order, after the indirect dispatch that composites them (one
    #: group a tile: `_OCCUPIED_HEADER`)
    occupied: int


class GpuTileBinning:
    """The binning's programs and buffers; `bin` bins one draw."""

    def __init__(self):
        defines = {"TILE_PIXELS": TILE_PIXELS}
        self._programs = {
            stage: build_compute_program("tile_bin", defines | {stage: 1}) for stage in ("COUNT", "EMIT", "STARTS")
        }
        self._uniforms = {stage: uniform_locations(program, _UNIFORMS) for stage, program in self._programs.items()}
        self._buffers = GL.glGenBuffers(7)
        self._counter, self._slots, self._tiles, self._starts, self._pair_starts, self._discs, self._occupied = (
            self._buffers
        )
        self._pair_capacity = self._tile_capacity = self._slot_capacity = 0
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
        for a screen of `size` pixels seen with `view` and `projection`; `pairs` 0 when no splat touches the
        screen, None when there would be more than `MAX_PAIRS` (the raster draws those)."""
        buffer, first, slots = instances
        across, up = -(-size[0] // TILE_PIXELS), -(-size[1] // TILE_PIXELS)
        empty = BinnedTiles(tuple(size), across, up, self._starts, self._slots, 0, self._discs, self._occupied)
        if not slots:
            return empty
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._counter)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, 4, np.zeros(1, dtype=np.uint32), GL.GL_STREAM_COPY)
        if slots > self._slot_capacity:
            self._slot_capacity = max(slots, 2 * self._slot_capacity)
            reallocate_storage((self._pair_starts,), 4 * self._slot_capacity)
            reallocate_storage((self._discs,), _DISC_BYTES * self._slot_capacity)
        GL.glBindBufferRange(
            GL.GL_SHADER_STORAGE_BUFFER, _INSTANCES, buffer, first * INSTANCE_BYTES, slots * INSTANCE_BYTES
        )
        # without a command, the counter stands in for it: a shader's storage blocks must all be bound
        count_at = (self._counter, _ALL_SLOTS) if count_at is None else count_at
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _COMMAND, count_at[0])
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _COUNTER, self._counter)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_STARTS, self._pair_starts)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, DISCS_BINDING, self._discs)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        self._dispatch("COUNT", slots, count_at[1], view, projection, size, (across, up))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        self._prefix_sum.scan(self._pair_starts, slots)  # issued before the read-back waits: the GPU goes on
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._counter)
        pairs = int(np.frombuffer(GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, 4), dtype=np.uint32)[0])
        if not pairs or pairs > MAX_PAIRS:
            return None if pairs else empty
        self._reserve(pairs, across * up + 1)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_SLOTS, self._slots)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_TILES, self._tiles)
        self._dispatch("EMIT", slots, count_at[1], view, projection, size, (across, up))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        # the pairs in the draw's order (far to near), sorted stably by tile: each tile's run keeps that order
        self._sort.sort(self._tiles, self._slots, pairs, key_bits=key_bits_for(across * up - 1))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _PAIR_TILES, self._tiles)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TILE_STARTS, self._starts)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._occupied)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, _OCCUPIED_HEADER.nbytes, _OCCUPIED_HEADER)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, OCCUPIED_BINDING, self._occupied)
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        program, uniforms = self._programs["STARTS"], self._uniforms["STARTS"]
        GL.glUseProgram(program)
        GL.glUniform1ui(uniforms["pairs"], pairs)
        GL.glUniform1ui(uniforms["max_groups"], max_dispatch_groups())
        GL.glUniform1i(uniforms["tiles_across"], across)
        GL.glUniform1i(uniforms["tiles_up"], up)
        dispatch(-(-pairs // _GROUP))
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_COMMAND_BARRIER_BIT)
        return BinnedTiles(tuple(size), across, up, self._starts, self._slots, pairs, self._discs, self._occupied)

    def read(self, binned: BinnedTiles) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(starts, entries, occupied tiles, their dispatch's groups) of `binned` read back, as `ScreenTiles` holds
        the first three (the tests compare them)."""
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        header = self._read(binned.occupied, 0, len(_OCCUPIED_HEADER))
        starts = self._read(binned.starts, 0, binned.across * binned.up + 1)
        occupied = self._read(binned.occupied, len(_OCCUPIED_HEADER), int(header[3]))
        return starts, self._read(binned.entries, 0, binned.pairs), occupied, header[:3]

    @staticmethod
    def _read(buffer: int, first: int, count: int) -> np.ndarray:
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
        data = GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 4 * first, 4 * count) if count else b""
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        return np.frombuffer(data, np.uint32).copy()

    def _dispatch(self, stage: str, slots: int, count_at: int, view, projection, size, tiles) -> None:
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
