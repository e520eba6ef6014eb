"""The passes of a frame timed on one timeline, the GPU left to run behind the CPU until the frame ends.

A frame's passes are issued one after the other with no wait between them:
while the GPU works through one pass, the CPU plans and issues the next, and
the frame ends with one glFinish.  Each pass is timed three ways:

- its **CPU** time: from its start to its last command issued (Python, numpy,
  the driver's calls);
- its **GPU** time: the difference of two GL_TIMESTAMP queries, recorded when
  the GPU reaches the pass's first command and finishes its last (GL 3.3
  core).  A GL_TIME_ELAPSED query would say the same, but llvmpipe loses its
  start when the first pass of a context makes its resources and reports the
  raw end timestamp.  llvmpipe bins a timestamp into every screen tile with
  the draws around it and answers with the time its threads rasterised the
  last of those tiles, so the first query is flushed on its own: binned with
  the pass's draws it came back at their last tile, and a 5 ms cloud pass
  took 0.04 ms of GPU time.  Its compute dispatches run on the CPU's thread
  as they are issued, so there a compute pass shows as CPU time;
- its **wall** time: what it added to the frame.  A pass is over when both
  the CPU has issued it and the GPU has finished it, whichever is later; the
  GPU's timestamps are put on the CPU's clock by reading the GPU's clock
  (glGetInteger64v(GL_TIMESTAMP), the GPU's time when the call reaches it,
  whatever it is still running) when the frame starts.  A
  pass's wall time runs from the end of the pass before (from the frame's
  start, for the first) to its own end, so the passes' wall times add up to
  the frame's, and what the CPU did between two passes counts to the second.

The wall time is what the cost model fits (`LodState.measured`).  Before, each
pass ended with its own glFinish, and the GPU idled while the CPU issued the
next pass: impostor and auto frames took 2-6% longer on llvmpipe, whose
rasteriser shares the cores with the Python issuing the next pass
(docs/performance.md, "One wait a frame").  A pass that keeps the
GPU busy shows GPU near wall; one bound by the CPU shows CPU near wall.  The
queries are read after the frame's glFinish, so reading them never waits.
"""

from __future__ import annotations

import ctypes
import time
from contextlib import contextmanager
from dataclasses import dataclass

from OpenGL import GL


@dataclass(frozen=True)
class PassTime:
    wall_ms: float  # what the pass added to its frame: from the end of the pass before to its own end
    cpu_ms: float  # from its start to its last command issued
    gpu_ms: float  # from the GPU reaching its first command to finishing its last


@dataclass(frozen=True)
class _Issued:
    """One pass as the CPU issued it: its queries and its times on the CPU's clock (seconds)."""

    began_query: int
    ended_query: int
    started: float
    issued: float


class PassClock:
    """Times the passes of a frame (`frame`, then `timed` for each); `times` holds the last frame's by name."""

    def __init__(self):
        self._queries: list[int] = []  # pairs, reused frame after frame
        self._issued: dict[str, _Issued] = {}
        self._frame_started: float | None = None
        self._gpu_offset_s = 0.0  # the GPU's clock minus the CPU's, in seconds
        self.times: dict[str, PassTime] = {}

    @contextmanager
    def frame(self):
        """Time the passes `timed` in the body as one frame, ended by a glFinish; `times` then holds them."""
        if self._frame_started is not None:
            raise RuntimeError("a frame's passes are being timed already")
        self._gpu_offset_s = 1e-9 * _gpu_clock_ns() - time.perf_counter()
        self._frame_started = time.perf_counter()
        self._issued = {}
        try:
            yield
            GL.glFinish()
            finished = time.perf_counter()
            self.times = self._times(finished)
        finally:
            self._frame_started = None

    @contextmanager
    def timed(self, name: str):
        """Time the body as pass `name` of the frame being timed; it ends with a glFlush, not a glFinish: the GPU
        may still be running it."""
        if self._frame_started is None:
            raise RuntimeError(f"pass {name!r} is timed outside a frame (PassClock.frame)")
        if name in self._issued:
            raise ValueError(f"pass {name!r} is timed twice in one frame")
        pair = 2 * len(self._issued)
        if pair >= len(self._queries):
            self._queries += [int(query) for query in GL.glGenQueries(2)]
        began, ended = self._queries[pair : pair + 2]
        GL.glQueryCounter(began, GL.GL_TIMESTAMP)
        GL.glFlush()  # on its own, not binned with the pass's draws (above)
        started = time.perf_counter()
        yield
        issued = time.perf_counter()
        GL.glQueryCounter(ended, GL.GL_TIMESTAMP)
        GL.glFlush()  # hands the pass to the GPU now: a driver may hold commands back until its buffer fills
        self._issued[name] = _Issued(began, ended, started, issued)

    def _times(self, finished: float) -> dict[str, PassTime]:
        """Each pass's times, once the frame's glFinish returned at `finished` (CPU clock, seconds)."""
        times = {}
        names = list(self._issued)
        previous_end = self._frame_started
        for index, name in enumerate(names):
            issued = self._issued[name]
            gpu_began, gpu_ended = (
                1e-9 * _timestamp_ns(q) - self._gpu_offset_s for q in (issued.began_query, issued.ended_query)
            )
            # the last pass ends when the frame's glFinish returned; the others when both clocks say they are done
            end = finished if index == len(names) - 1 else max(issued.issued, gpu_ended)
            end = min(max(end, previous_end), finished)
            times[name] = PassTime(
                1e3 * (end - previous_end),
                1e3 * (issued.issued - issued.started),
                1e3 * max(gpu_ended - gpu_began, 0.0),
            )
            previous_end = end
        return times

    def close(self) -> None:
        if self._queries:
            GL.glDeleteQueries(len(self._queries), self._queries)
        self._queries = []


def _gpu_clock_ns() -> int:
    """The GPU's clock now (GL_TIMESTAMP, nanoseconds): when the call reaches it, not after what it is running."""
    value = ctypes.c_int64()
    GL.glGetInteger64v(GL.GL_TIMESTAMP, ctypes.byref(value))
    return value.value


def _timestamp_ns(query: int) -> int:
    value = ctypes.c_uint64()
    GL.glGetQueryObjectui64v(query, GL.GL_QUERY_RESULT, ctypes.byref(value))
    return value.value
