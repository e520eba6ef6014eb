"""A stable radix sort on the GPU of (key, value) uint32 pairs held in storage buffers.

The GPU counterpart of `cloudcore.particles.depth_order.far_to_near`: given keys
that are the inverted bit patterns of float32 distances, sorting them
ascending orders the values (particle indices) far to near, equal distances
in their input order, exactly as the CPU does.  Eight passes of four bits
(fewer for shorter keys), each a count, a prefix sum of the counts (`cloudcore.gl.prefix_sum`) and a
scatter (`shaders/depth_sort.comp.glsl`), ping-ponging between
the caller's buffers and two of its own, so the sorted pairs end where they
began.  No data comes back to the CPU: what draws from the order reads it
where it is.
"""

from __future__ import annotations

from OpenGL import GL

from cloudcore.gl.measured_way import software_rasterizer
from cloudcore.gl.prefix_sum import GpuPrefixSum
from cloudcore.gl.programs import build_compute_program, gl_renderer, uniform_locations

#: bits of the key a pass sorts by; see the shader for why four
DIGIT_BITS = 4
#: keys one invocation takes, per kind of GL (256 invocations a workgroup make a tile of 256 times that).  A
#: workgroup's scan of its invocations' digit counts costs the same whatever its tile: a GPU runs many
#: workgroups at once, so small tiles keep it busy (the H200's times in docs/performance.md are with 8); llvmpipe
#: runs each on one thread, stepping its 256 invocations through the scan's 16 barriers, so large tiles
#: amortise them, 128 as well as 256 (docs/performance.md, "The GPU's order")
ITEMS_ON_GPU, ITEMS_ON_CPU = 8, 128
_STAGES = ("COUNT", "SCATTER")
#: the shader's storage bindings, past the prefix sum's, so a pass binds its buffers once for both stages
_KEYS_IN, _VALUES_IN, _KEYS_OUT, _VALUES_OUT, _TILE_COUNTS, _COUNTED = range(2, 8)
#: the shader's `count_at` for a count the CPU gives
_COUNT_GIVEN = 0xFFFFFFFF


class GpuDepthSort:
    def __init__(self, items: int | None = None):
        """`items`: the keys an invocation takes, by default this GL's (`ITEMS_ON_GPU`, `ITEMS_ON_CPU`)."""
        if items is None:
            items = ITEMS_ON_CPU if software_rasterizer(gl_renderer()) else ITEMS_ON_GPU
        self._tile = 256 * items
        defines = {"DIGIT_BITS": DIGIT_BITS, "ITEMS": items}
        self._programs = {stage: build_compute_program("depth_sort", defines | {stage: 1}) for stage in _STAGES}
        self._uniforms = {
            stage: uniform_locations(program, ("count", "count_at", "shift", "tiles"))
            for stage, program in self._programs.items()
        }
        self._scratch_keys, self._scratch_values, self._tile_counts = self._buffers = GL.glGenBuffers(3)
        self._capacity = 0  # pairs the scratch buffers hold
        self._prefix_sum = GpuPrefixSum()

    def sort(
        self, keys: int, values: int, count: int, key_bits: int = 32, count_at: tuple[int, int] | None = None
    ) -> None:
        """Sort the first `count` pairs of buffers `keys` and `values` by key, in place, stably; keys below
        2**`key_bits` need only that many bits sorted (a multiple of 8: the pairs end where they began
        after an even count of passes).  Where only the GPU knows how many pairs there are, `count_at` says
        where (a storage buffer, a uint's index in it) and `count` is the most there can be: the lesser is
        sorted, and the CPU need not wait to read it (the tile binning's pairs).

        The caller orders its writes to the buffers before this with a storage barrier, and its reads after
        it with the barrier its reads need; between the passes this issues its own."""
        if key_bits % (2 * DIGIT_BITS) or not 0 < key_bits <= 32:
            raise ValueError(f"the sort takes keys of 8, 16, 24 or 32 bits, not {key_bits}")
        if count <= 1:
            return
        self._reserve(count)
        tiles = -(-count // self._tile)
        # what every pass shares is set once: a frame sorts a few times, 8 passes of 2 stages each, and each GL
        # call costs the CPU a microsecond or two (the default flythrough's full 3D: 2 sorts a frame)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _TILE_COUNTS, self._tile_counts)
        # without a count on the GPU, the tile counts stand in for its buffer: a shader's blocks must all be bound
        counted, index = (self._tile_counts, _COUNT_GIVEN) if count_at is None else count_at
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _COUNTED, counted)
        for stage, program in self._programs.items():
            GL.glUseProgram(program)
            GL.glUniform1ui(self._uniforms[stage]["count"], count)
            GL.glUniform1ui(self._uniforms[stage]["count_at"], index)
            GL.glUniform1ui(self._uniforms[stage]["tiles"], tiles)
        sources, targets = (keys, values), (self._scratch_keys, self._scratch_values)
        for sort_pass in range(key_bits // DIGIT_BITS):
            for binding, buffer in zip((_KEYS_IN, _VALUES_IN, _KEYS_OUT, _VALUES_OUT), sources + targets):
                GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, binding, buffer)
            self._run("COUNT", sort_pass * DIGIT_BITS, tiles)
            self._prefix_sum.scan(self._tile_counts, tiles << DIGIT_BITS)  # each (digit, tile) run's start
            self._run("SCATTER", sort_pass * DIGIT_BITS, tiles)
            sources, targets = targets, sources

    def _run(self, stage: str, shift: int, tiles: int) -> None:
        """One stage of a pass, on the digit from bit `shift`, over `tiles` workgroups."""
        GL.glUseProgram(self._programs[stage])
        GL.glUniform1ui(self._uniforms[stage]["shift"], shift)
        GL.glDispatchCompute(tiles, 1, 1)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)

    def _reserve(self, count: int) -> None:
        if count <= self._capacity:
            return
        capacity = max(count, 2 * self._capacity)
        tiles = -(-capacity // self._tile)
        for buffer, size in (
            (self._scratch_keys, 4 * capacity),
            (self._scratch_values, 4 * capacity),
            (self._tile_counts, 4 * tiles << DIGIT_BITS),
        ):
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, size, None, GL.GL_DYNAMIC_COPY)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        self._capacity = capacity

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        for program in self._programs.values():
            GL.glDeleteProgram(program)
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))
        self._prefix_sum.close()


def key_bits_for(largest: int) -> int:
    """The fewest bits `GpuDepthSort.sort` takes (whole bytes) for keys up to `largest`."""
    return 8 * max(1, -(-max(int(largest), 1).bit_length() // 8))
