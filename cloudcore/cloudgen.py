"""Deterministic cumulus particle clouds: a flat base with heaped domes on top.

A cumulus is modelled as the union of ellipsoidal "turrets" resting on a
common flat bottom (the condensation level), filled by rejection sampling with
particles whose radii vary around a base size.  Same seed, same cloud (the
shipped scenes also store the particles, so goldens never depend on numpy's
generator streams).
"""

from __future__ import annotations

import numpy as np


def cumulus(centre, size, count: int, particle_radius: float, seed: int) -> np.ndarray:
    """Particles (count, 4) as (x, y, z, radius) for a cumulus whose base centre is `centre`.

    `size` = (width x, height y, depth z) in metres; the base sits at centre y.
    """
    rng = np.random.default_rng(seed)
    width, height, depth = (float(v) for v in size)
    centre = np.asarray(centre, dtype=np.float64)
    turrets = max(3, int(rng.integers(4, 8)))
    offsets = rng.uniform(-0.5, 0.5, (turrets, 3)) * np.array([width * 0.55, 0.0, depth * 0.55])
    radii = np.stack([
        rng.uniform(0.30, 0.45, turrets) * width,
        rng.uniform(0.55, 1.0, turrets) * height,
        rng.uniform(0.30, 0.45, turrets) * depth,
    ], axis=1)
    # the biggest turret sits in the middle so the cloud has a dominant head
    offsets[0] = 0.0
    radii[0] = (0.5 * width, height, 0.5 * depth)

    accepted = np.zeros((0, 3))
    while len(accepted) < count:
        batch = rng.uniform(-0.5, 0.5, (4 * count, 3)) * np.array([width * 1.3, 2 * height, depth * 1.3])
        batch[:, 1] = np.abs(batch[:, 1])  # flat bottom: nothing below the base
        inside = np.zeros(len(batch), dtype=bool)
        for offset, radius in zip(offsets, radii):
            inside |= (((batch - offset) / radius) ** 2).sum(axis=1) <= 1.0
        accepted = np.concatenate([accepted, batch[inside]])
    positions = centre + accepted[:count]
    # bigger puffs deep inside, smaller at the rim keep the silhouette crisp
    reach = np.min([(((accepted[:count] - o) / r) ** 2).sum(axis=1) for o, r in zip(offsets, radii)], axis=0)
    radius = particle_radius * rng.uniform(0.75, 1.25, count) * (1.15 - 0.35 * np.sqrt(np.clip(reach, 0, 1)))
    return np.column_stack([positions, radius])
