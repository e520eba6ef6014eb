"""Clouds that form from the core outward or dissipate from the edges (Wang 2004, section 4).

Wang animates a cloud by multiplying a transparency factor into every
sprite's alpha, chosen by where the sprite sits in the cloud: a forming cloud
shows the sprites within half the cloud radius first, fading them in, and
the outer sprites only after those have reached a threshold opacity;
dissipation reverses the process, so the edges vanish first.  Listing 1 of
the magazine version computes that factor as a straight line in the distance
from the cloud centre whose offset moves with time,
`alpha_of_cloud - radial_magnitude * alpha_at_edges / cloud_radius`.

Here the line is `2 progress - distance` clipped to [0, 1], with `distance`
the particle's distance from the cloud's core over the distance of the
farthest particle: the core fades in over the first half of the animation
and the edge over the second, each particle taking half the animation, so at
every instant opacity falls from core to edge.  Dissipation is formation
played backwards.  Outside the animation the factor is exactly 0 or 1.
"""

from __future__ import annotations

import math

import numpy as np

from cloudcore.model.cloud_records import Formation

#: fraction of the animation by which the farthest particle lags the core:
#: one half, so the edge starts when the core is fully opaque (Wang section 4)
EDGE_LAG = 0.5


def progress(formation: Formation, time_s: float) -> float:
    """How far the animation has run at `time_s`: 0 before it starts, 1 from its end on.

    A duration of 0 jumps from 0 to 1 at `start_s`.
    """
    if not math.isfinite(time_s):
        raise ValueError(f"time_s must be finite, got {time_s}")
    elapsed = time_s - formation.start_s
    if elapsed < 0:
        return 0.0
    if elapsed >= formation.duration_s:
        return 1.0
    return elapsed / formation.duration_s


def core_distances(centres: np.ndarray) -> np.ndarray:
    """Each particle's distance from the cloud's core over the farthest particle's, in [0, 1].

    The core is the centre of the box around the particle centres (Listing 1
    measures from the centre of the cloud's bounding box).  A cloud whose
    particles all sit at one point has every distance 0.
    """
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    if len(centres) == 0:
        return np.zeros(0)
    # halves before the sum and a rescale before the norm: no overflow for any finite coordinates
    core = 0.5 * centres.min(axis=0) + 0.5 * centres.max(axis=0)
    offsets = centres - core
    largest = np.abs(offsets).max()
    if not largest > 0:
        return np.zeros(len(centres))
    distance = np.linalg.norm(offsets / largest, axis=1)
    return np.clip(distance / distance.max(), 0.0, 1.0)


def opacity_factor(formation: Formation, distances: np.ndarray, time_s: float) -> np.ndarray:
    """The factor in [0, 1] that multiplies each particle's colour and opacity at `time_s`.

    `distances` come from `core_distances`.  Forming, the factor never falls
    with time and never rises with distance; dissipating, it never rises with
    time and never rises with distance.
    """
    distances = np.asarray(distances, dtype=np.float64)
    if np.isnan(distances).any():
        raise ValueError("core distances must not be NaN")
    done = progress(formation, time_s)
    return formed(1.0 - done if formation.kind == "dissipate" else done, distances)


def formed(done: float, order: np.ndarray) -> np.ndarray:
    """Each particle's share formed when `done` in [0, 1] of the cloud has: a particle of `order` in [0, 1] (0 the
    core's, first; 1 the edge's, last) starts at `EDGE_LAG order` and takes the rest of the animation less the lag;
    exactly 0 at `done` 0 and 1 at `done` 1."""
    order = np.asarray(order, dtype=np.float64)
    if done <= 0.0:
        return np.zeros(order.shape)
    if done >= 1.0:
        return np.ones(order.shape)
    return np.clip((done - EDGE_LAG * order) / (1.0 - EDGE_LAG), 0.0, 1.0)


def progress_for_share(share: float) -> float:
    """The progress at which `formed` gives a cloud whose particles' orders spread evenly over [0, 1] `share` of its
    opacity: its mean is 2 p^2 up to p = 1/2 and 1 - 2 (1 - p)^2 beyond (with `EDGE_LAG` 1/2), inverted."""
    share = min(max(share, 0.0), 1.0)
    return math.sqrt(0.5 * share) if share <= 0.5 else 1.0 - math.sqrt(0.5 * (1.0 - share))


def formation_state(formation: Formation | None, time_s: float):
    """A hashable value that stays the same while the cloud's opacity factors cannot change.

    It is constant before and after the animation (and always for a cloud
    without one) and changes with every instant inside it, so a renderer
    remakes a cloud's impostors only while it forms or dissipates.
    """
    if formation is None:
        return None
    return formation.kind, progress(formation, time_s)
