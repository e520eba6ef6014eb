"""Recording a camera path: the frame times at a frame rate, and one statistics row per frame (numpy only)."""

from __future__ import annotations

import math

import numpy as np

#: the columns of `cloudview record --stats`, in order; other_ms is frame_ms less the cloud pass and impostor updates
COLUMNS = (
    "frame",
    "time_s",
    "frame_ms",
    "cloud_ms",
    "impostor_update_ms",
    "other_ms",
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


def frame_times(duration: float, fps: float, frames: int | None = None) -> np.ndarray:
    """Seconds from the path's start of frame i = 0, 1, ...: i / fps, up to `duration` included.

    A 30 s path at 30 fps is 901 frames, the last at 30 s.  With `frames`,
    only the first `frames` of them.
    """
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be finite and > 0, got {fps}")
    # rounded first: 1.16 s * 25 fps is 28.999999999999996 in floating point, and is 29 frame steps
    count = math.floor(round(duration * fps, 9)) + 1
    if frames is not None:
        count = min(count, frames)
    return np.arange(count) / fps


def frame_row(frame: int, time_s: float, stats: dict) -> dict:
    """The `COLUMNS` of one frame from `FrameRenderer.render`'s stats, with `measure_overdraw`'s if measured.

    Overdraw not measured is left empty; layer counts a renderer does not
    report are 0 (it has no split layers).
    """
    ms = {key: round(stats[key], 3) for key in ("frame_ms", "cloud_ms", "impostor_update_ms")}
    overdraw = {
        key: round(stats[key], 4) if key in stats else ""
        for key in ("overdraw_mean", "overdraw_max", "overdraw_analytic")
    }
    return {
        "frame": frame,
        "time_s": round(time_s, 6),
        **ms,
        "other_ms": round(stats["frame_ms"] - stats["cloud_ms"] - stats["impostor_update_ms"], 3),
        **{
            key: stats[key]
            for key in ("particles_drawn", "clouds_drawn", "impostors_drawn", "impostors_regenerated", "texture_bytes")
        },
        "layers_drawn": stats.get("layers_drawn", 0),
        "layers_rebuilt": stats.get("layers_rebuilt", 0),
        **overdraw,
    }
