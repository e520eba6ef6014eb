"""The far-to-near sort on the CPU (`cloudcore.particles.depth_order.far_to_near`) against the GPU's radix sort
(`cloudcore.gl.depth_sort.GpuDepthSort`), side by side in one run, with their orders compared. JSON out.

    python scripts/bench_gpu_sort.py [--counts 10000,100000,1000000] [--repeat 7] [--json out/bench_gpu_sort.json]

Per count: the distances of particles of a random cloud field from an eye inside it; the CPU sorts them
from float64 distances (what `splat_batch` does), the GPU sorts the same keys already in its buffers (what a
`SplatSelection` does after choosing).  Times are the median of --repeat, the GPU's to glFinish and on its
own clock (GL_TIMESTAMP), the first run (compiling, allocating) left out.  `equal` says whether the GPU's
order is the CPU's, exactly.

`incremental_ms` times the other way to cut the CPU's sort that issue 23 names: re-sorting from the last
frame's order (FlightGear's per-cloud pass does so), with the eye one frame of the flythrough (5 m) away.
numpy's stable sort of 64-bit keys (the distance key over the index, so ties break as the radix sort's do)
is a timsort, which runs in linear time on an order that is already nearly sorted.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from OpenGL import GL  # noqa: E402  (the GL imports need the platform)

from cloudcore.gl.context import HeadlessContext  # noqa: E402
from cloudcore.gl.depth_sort import GpuDepthSort  # noqa: E402
from cloudcore.gl.pass_clock import PassClock  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.particles.depth_order import distance_keys, far_to_near  # noqa: E402

#: how far the default flythrough's eye moves in a frame: 150 m/s at 30 fps
_FRAME_STEP_M = 5.0


def resorted(distances: np.ndarray, last_order: np.ndarray) -> np.ndarray:
    """`far_to_near(distances)`, sorted starting from `last_order` (a nearly sorted permutation)."""
    indices = np.arange(len(distances), dtype=np.uint64)
    keys = (distance_keys(distances).astype(np.uint64) << np.uint64(32)) | indices
    return last_order[np.argsort(keys[last_order], kind="stable")]


def bench(count: int, repeat: int, sort: GpuDepthSort, buffers, clock: PassClock) -> dict:
    rng = np.random.default_rng(count)
    centres = rng.normal(size=(count, 3)) * [3000.0, 400.0, 3000.0]
    distances = np.linalg.norm(centres, axis=1)
    last_frames_order = far_to_near(np.linalg.norm(centres - [_FRAME_STEP_M, 0.0, 0.0], axis=1))
    cpu_ms, incremental_ms, gpu_wall_ms, gpu_ms = [], [], [], []
    for _ in range(repeat + 1):
        started = time.perf_counter()
        cpu_order = far_to_near(distances)
        cpu_ms.append(1e3 * (time.perf_counter() - started))
        started = time.perf_counter()
        incremental_order = resorted(distances, last_frames_order)
        incremental_ms.append(1e3 * (time.perf_counter() - started))
        for buffer, data in zip(buffers, (distance_keys(distances), np.arange(count, dtype=np.uint32))):
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, data.nbytes, data, GL.GL_DYNAMIC_COPY)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        GL.glFinish()
        with clock.frame(), clock.timed("sort"):  # a frame of one pass: timed to its glFinish
            sort.sort(*buffers, count)
        gpu_wall_ms.append(clock.times["sort"].wall_ms)
        gpu_ms.append(clock.times["sort"].gpu_ms)
    GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffers[1])
    gpu_order = np.frombuffer(GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, 4 * count), dtype=np.uint32)
    median = lambda times: float(np.median(times[1:]))  # noqa: E731
    row = {
        "count": count,
        "cpu_ms": median(cpu_ms),
        "incremental_ms": median(incremental_ms),
        "incremental_equal": bool(np.array_equal(incremental_order, cpu_order)),
        "gpu_wall_ms": median(gpu_wall_ms),
        "gpu_ms": median(gpu_ms),
        "equal": bool(np.array_equal(gpu_order, cpu_order)),
    }
    row["gpu_over_cpu"] = row["gpu_wall_ms"] / row["cpu_ms"]
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--counts", default="10000,100000,1000000")
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--json", type=Path, default=Path("out/bench_gpu_sort.json"))
    args = parser.parse_args()
    context = HeadlessContext(64, 64)
    context.make_current()
    sort, buffers, clock = GpuDepthSort(), GL.glGenBuffers(2), PassClock()
    rows = []
    for count in (int(text) for text in args.counts.split(",")):
        rows.append(bench(count, args.repeat, sort, buffers, clock))
        row = rows[-1]
        print(
            f"{row['count']:>9,} keys: CPU {row['cpu_ms']:8.2f} ms, from the last frame's order "
            f"{row['incremental_ms']:8.2f} ms (same order: {row['incremental_equal']}), "
            f"GPU {row['gpu_wall_ms']:8.2f} ms to glFinish "
            f"({row['gpu_ms']:.2f} on its clock), x{row['gpu_over_cpu']:.1f}, same order: {row['equal']}"
        )
    sort.close()
    GL.glDeleteBuffers(2, list(buffers))
    clock.close()
    context.close()
    write_report({"machine": machine(), "counts": rows}, args.json)


if __name__ == "__main__":
    main()
