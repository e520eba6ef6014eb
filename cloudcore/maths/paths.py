"""Keyframed paths: smooth interpolation of (t, values...) rows.

Uniform Catmull-Rom through the keys (C1, passes through every key), with the
end keys repeated; time outside the keys clamps to the ends.
"""

from __future__ import annotations

import numpy as np

from cloudcore.model.scene import Camera


def sample(keys: np.ndarray, t: float) -> np.ndarray:
    """Values at time `t` of rows (t, v...), keys sorted by strictly increasing time."""
    keys = np.asarray(keys, dtype=np.float64)
    times, values = keys[:, 0], keys[:, 1:]
    if len(keys) == 1 or t <= times[0]:
        return values[0].copy()
    if t >= times[-1]:
        return values[-1].copy()
    i = int(np.searchsorted(times, t, side="right")) - 1
    p0, p1 = values[max(i - 1, 0)], values[i]
    p2, p3 = values[i + 1], values[min(i + 2, len(values) - 1)]
    s = (t - times[i]) / (times[i + 1] - times[i])
    # tangents scaled to the neighbouring intervals so uneven key spacing stays smooth
    dt = times[i + 1] - times[i]
    m1 = (p2 - p0) / max(times[min(i + 1, len(times) - 1)] - times[max(i - 1, 0)], 1e-300) * dt
    m2 = (p3 - p1) / max(times[min(i + 2, len(times) - 1)] - times[i], 1e-300) * dt
    s2, s3 = s * s, s * s * s
    return (2 * s3 - 3 * s2 + 1) * p1 + (s3 - 2 * s2 + s) * m1 + (-2 * s3 + 3 * s2) * p2 + (s3 - s2) * m2


def camera_on_path(path, t: float, fov_y_deg: float) -> Camera:
    """The `Camera` a `CameraPath` gives at time `t` (seconds from the path's start time)."""
    at = sample(path.keys, path.keys[0, 0] + t)
    return Camera(tuple(float(v) for v in at[:3]), tuple(float(v) for v in at[3:]), fov_y_deg)


def frame_times(path, frames: int) -> np.ndarray:
    """`frames` times (seconds from the path's start) spread evenly over the path, ends included."""
    if frames < 1:
        raise ValueError(f"frames must be >= 1, got {frames}")
    return np.linspace(0.0, path.duration, frames) if frames > 1 else np.zeros(1)
