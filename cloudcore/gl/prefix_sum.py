"""Exclusive prefix sums of a uint32 storage buffer on the GPU, in place (`shaders/prefix_sum.comp.glsl`).

Where each item of a parallel pass writes a number of outputs, the sums of the counts before it say where its
own go, in the items' order, with no atomic counter to shuffle them (the tile binning's pairs), and the radix
sort's per-digit run starts are the same sums over its counts.  Blocks of `BLOCK` items are summed, their sums
scanned by one workgroup, and each block scanned from its start: three dispatches, or one (the workgroup's scan
alone) for up to `ONE_GROUP_ITEMS`.
"""

from __future__ import annotations

from OpenGL import GL

from cloudcore.gl.programs import build_compute_program

#: items one invocation sums in order; 256 invocations a workgroup make a block
ITEMS = 8
BLOCK = 256 * ITEMS
#: items scanned by one workgroup alone, 128 an invocation: the radix sort's digit counts up to 4.2 million keys,
#: which its single-workgroup scan took before this module (measured on the H200: docs/performance.md), so its
#: dispatches are what they were there; longer arrays (the tile binning's slots) take the three stages
ONE_GROUP_ITEMS = 16 * BLOCK
_STAGES = ("BLOCK_SUMS", "SCAN", "BLOCKS")
_VALUES, _BLOCK_SUMS = 0, 1


class GpuPrefixSum:
    def __init__(self):
        self._programs = {stage: build_compute_program("prefix_sum", {"ITEMS": ITEMS, stage: 1}) for stage in _STAGES}
        self._counts = {stage: GL.glGetUniformLocation(program, "count") for stage, program in self._programs.items()}
        self._block_sums = GL.glGenBuffers(1)
        self._capacity = 0  # blocks the block sums' buffer holds

    def scan(self, buffer: int, count: int) -> None:
        """Replace the first `count` uints of storage buffer `buffer` by the sums of those before each (up to
        65,535 blocks, 134 million items: the GL's fewest work groups a dispatch).

        The caller orders its writes to the buffer before this with a storage barrier, and its reads after
        it with the barrier its reads need (this issues a storage barrier last)."""
        if count <= 0:
            return
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _VALUES, buffer)
        if count <= ONE_GROUP_ITEMS:
            self._run("SCAN", 1, count)
            return
        blocks = -(-count // BLOCK)
        self._reserve(blocks)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _BLOCK_SUMS, self._block_sums)
        self._run("BLOCK_SUMS", blocks, count)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _VALUES, self._block_sums)
        self._run("SCAN", 1, blocks)
        GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, _VALUES, buffer)
        self._run("BLOCKS", blocks, count)

    def _run(self, stage: str, groups: int, count: int) -> None:
        GL.glUseProgram(self._programs[stage])
        GL.glUniform1ui(self._counts[stage], count)
        GL.glDispatchCompute(groups, 1, 1)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)

    def _reserve(self, blocks: int) -> None:
        if blocks > self._capacity:
            self._capacity = max(blocks, 2 * self._capacity)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self._block_sums)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, 4 * self._capacity, None, GL.GL_DYNAMIC_COPY)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        for program in self._programs.values():
            GL.glDeleteProgram(program)
        GL.glDeleteBuffers(1, [self._block_sums])
