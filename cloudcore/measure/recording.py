"""Recording a camera path: the frame times at a frame rate, and one statistics row per frame (numpy only)."""

from __future__ import annotations

import math

import numpy as np

from cloudcore.stats.frame_stats import FrameStats

#: the columns of `cloudview record --stats`, in order; other_ms is frame_ms less the cloud pass and impostor updates
#: (the plan and the world),
#: cpu_ms the CPU's part of the frame and gpu_ms the GPU's time on its passes (`FrameStats`)
COLUMNS = (
    "frame",
    "time_s",
    "frame_ms",
    "cloud_ms",
    "impostor_update_ms",
    "other_ms",
    "cpu_ms",
    "gpu_ms",
    "particles_drawn",
    "clouds_drawn",
    "impostors_drawn",
    "impostors_regenerated",
    "layers_drawn",
    "layers_rebuilt",
    "overdraw_mean",
    "overdraw_max",
    "overdraw_analytic",
    "texture_bytes",
)


#: the most frames one recording may have (92 hours at 30 fps): a path of 1e12 s asked for 3e13 frame times
MAX_RECORDED_FRAMES = 10_000_000


def frame_times(duration: float, fps: float, frames: int | None = None) -> np.ndarray:
    """Seconds from the path's start of frame i = 0, 1, ...: i / fps, up to `duration` included.

    A 30 s path at 30 fps is 901 frames, the last at 30 s.  With `frames`,
    only the first `frames` of them.
    """
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be finite and > 0, got {fps}")
    # rounded first: 1.16 s * 25 fps is 28.999999999999996 in floating point, and is 29 frame steps
    steps = round(duration * fps, 9)  # inf for a path of 1e12 s at 1e300 fps
    if frames is not None:
        steps = min(steps, frames - 1)
    if not steps < MAX_RECORDED_FRAMES:
        raise ValueError(
            f"a {duration:g} s path at {fps:g} fps is {steps + 1:.3g} frames, past the {MAX_RECORDED_FRAMES:,} a "
            "recording may have: give fewer frames (--frames) or a lower frame rate"
        )
    return np.arange(math.floor(steps) + 1) / fps


def frame_row(frame: int, time_s: float, stats: FrameStats) -> dict:
    """The `COLUMNS` of one frame from `FrameRenderer.render`'s stats; overdraw not measured is left empty."""
    overdraw = stats.overdraw
    return {
        "frame": frame,
        "time_s": round(time_s, 6),
        "frame_ms": round(stats.frame_ms, 3),
        "cloud_ms": round(stats.cloud_ms, 3),
        "impostor_update_ms": round(stats.impostor_update_ms, 3),
        "other_ms": round(stats.frame_ms - stats.cloud_ms - stats.impostor_update_ms, 3),
        "cpu_ms": round(stats.cpu_ms, 3),
        "gpu_ms": round(stats.world_gpu_ms + stats.impostor_update_gpu_ms + stats.cloud_gpu_ms, 3),
        "particles_drawn": stats.particles_drawn,
        "clouds_drawn": stats.clouds_drawn,
        "impostors_drawn": stats.plan.impostors_drawn,
        "impostors_regenerated": stats.plan.impostors_regenerated,
        "texture_bytes": stats.texture_bytes,
        "layers_drawn": stats.plan.layers_drawn,
        "layers_rebuilt": stats.plan.layers_rebuilt,
        "overdraw_mean": round(overdraw.mean, 4) if overdraw else "",
        "overdraw_max": round(overdraw.max, 4) if overdraw else "",
        "overdraw_analytic": round(overdraw.analytic, 4) if overdraw else "",
    }
