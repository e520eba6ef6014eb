"""Each pass of a frame timed three ways: on the wall clock to glFinish, on the CPU, and on the GPU.

The wall time to glFinish is what the cost model fits (`LodState.measured`) and
what the renderer has always reported.  Beside it: how long the CPU took to
issue the pass (Python, numpy, the driver's calls, up to the glFinish), and
how long the GPU took over it: the difference of two GL_TIMESTAMP queries,
recorded when the GPU reaches the pass's start and its end (GL 3.3 core;
llvmpipe answers them with its rasteriser threads' clock).  A GL_TIME_ELAPSED
query around the pass would say the same, but llvmpipe loses its start when the
first pass of a context makes its resources, and reports the raw end timestamp.
A pass that keeps the GPU busy shows GPU near wall; one bound by the CPU shows
CPU near wall, and its GPU time holds the gaps where the GPU waited for commands.
The queries are read after the pass's glFinish, so reading them never waits.
"""

from __future__ import annotations

import ctypes
import time
from contextlib import contextmanager
from dataclasses import dataclass

from OpenGL import GL


@dataclass(frozen=True)
class PassTime:
    wall_ms: float  # from the pass's start to its glFinish
    cpu_ms: float  # from its start to its last command issued
    gpu_ms: float  # from the GPU reaching its first command to finishing its last


class PassClock:
    """Times passes one after the other; `times` holds the last time of each pass by name."""

    def __init__(self):
        self._queries = [int(query) for query in GL.glGenQueries(2)]
        self.times: dict[str, PassTime] = {}

    @contextmanager
    def timed(self, name: str):
        """Time the body as pass `name`; it ends with a glFinish, so the next pass starts on an idle GPU."""
        began, ended = self._queries
        GL.glQueryCounter(began, GL.GL_TIMESTAMP)
        start = time.perf_counter()
        yield
        issued = time.perf_counter()
        GL.glQueryCounter(ended, GL.GL_TIMESTAMP)
        GL.glFinish()
        finished = time.perf_counter()
        gpu_ns = _timestamp_ns(ended) - _timestamp_ns(began)
        self.times[name] = PassTime(1e3 * (finished - start), 1e3 * (issued - start), 1e-6 * gpu_ns)

    def close(self) -> None:
        GL.glDeleteQueries(len(self._queries), self._queries)


def _timestamp_ns(query: int) -> int:
    value = ctypes.c_uint64()
    GL.glGetQueryObjectui64v(query, GL.GL_QUERY_RESULT, ctypes.byref(value))
    return value.value
