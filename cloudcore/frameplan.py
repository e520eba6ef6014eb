"""The frame plan: what each cloud costs this frame, decided before any GL call (pure numpy).

`plan_frame` turns (cloud bounding spheres, camera, viewport, settings, the
impostor cache, the ring state, the lighting) into a `FramePlan`: per cloud
one of

- ``empty``: no particles, nothing to draw;
- ``culled``: its bounding sphere misses the view frustum: no work at all;
- ``ring``: shown by Wang's ring of impostors only;
- ``full``: every particle drawn (near clouds, and every cloud in full mode);
- ``crossfade``: between `fade_start_radii` and `fade_end_radii` both the full
  cloud and its impostor, weights summing to one (the GL side mixes the two
  premultiplied images linearly, so the opacity is right throughout);
- ``impostor``: a textured quad, remade when `regenerate` names a reason;
- ``inside``: the eye is in the cloud: a screen-sized impostor at reduced
  resolution, redrawn every frame (Harris 3.1),

with the impostor cache and ring state to carry into the next frame.  The GL
side executes plans and nothing else; statistics come from the plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Hashable, Mapping

import numpy as np

from cloudcore.camera import frustum_planes, projection_matrix, spheres_in_frustum, view_matrix
from cloudcore.impostors import (INSIDE_RADII, ImpostorRecord, regeneration_reason, required_size,
                                 screen_size_px)
from cloudcore.ramps import smoothstep
from cloudcore.ring import RingPlan, RingState, plan_ring
from cloudcore.scene import Camera
from cloudcore.settings import RenderSettings

KINDS = ("empty", "culled", "ring", "full", "crossfade", "impostor", "inside")
#: kinds that draw from an impostor texture kept in the cache
TEXTURED = ("crossfade", "impostor")


@dataclass(frozen=True)
class CloudPlan:
    index: int
    kind: str
    distance: float
    full_weight: float = 0.0  # share of opacity drawn from particles (full, crossfade, inside)
    impostor_weight: float = 0.0  # share drawn from the cached impostor
    regenerate: str | None = None  # why the impostor is remade this frame
    texture_size: int = 0  # side of the impostor texture used


@dataclass(frozen=True)
class FramePlan:
    clouds: tuple
    draw_order: tuple  # indices of the clouds drawn individually, far to near
    ring: RingPlan | None
    records: Mapping = field(default_factory=dict)  # the impostor cache after this frame
    inside_size: tuple = (0, 0)  # the screen impostor's texture size (width, height)

    @property
    def ring_state(self) -> RingState:
        return self.ring.state if self.ring is not None else RingState()

    def of_kind(self, *kinds: str) -> list:
        return [c for c in self.clouds if c.kind in kinds]

    def stats(self) -> dict:
        counts = {f"clouds_{kind}": 0 for kind in KINDS}
        reasons: dict = {}
        for cloud in self.clouds:
            counts[f"clouds_{cloud.kind}"] += 1
            if cloud.regenerate:
                reasons[cloud.regenerate] = reasons.get(cloud.regenerate, 0) + 1
        return counts | {
            "impostors_drawn": len(self.of_kind(*TEXTURED)) + len(self.of_kind("inside")),
            "impostors_regenerated": sum(reasons.values()),
            "regeneration_reasons": reasons,
            "ring_segments_built": int(self.ring is not None and self.ring.build_segment is not None),
            "ring_panels_drawn": 8 * len(self.ring.draws) if self.ring is not None else 0,
        }


def plan_frame(centres: np.ndarray, radii: np.ndarray, camera: Camera, viewport: tuple[int, int],
               settings: RenderSettings, records: Mapping[int, ImpostorRecord], ring_state: RingState,
               lighting_key: Hashable) -> FramePlan:
    """Plan one frame; `centres` (N, 3) and `radii` (N,) are the clouds' bounding spheres.

    `lighting_key` identifies what the particles' colours were computed from: one key for
    all clouds, or a tuple with one per cloud (the editor changes one cloud at a time, and
    only that cloud's impostor is stale).
    """
    centres, radii = np.asarray(centres, dtype=np.float64).reshape(-1, 3), np.asarray(radii, dtype=np.float64)
    width, height = viewport
    eye = np.asarray(camera.position, dtype=np.float64)
    view_projection = projection_matrix(camera.fov_y_deg, width / height) @ view_matrix(camera)
    visible = spheres_in_frustum(frustum_planes(view_projection), centres, radii)
    distances = np.linalg.norm(centres - eye, axis=1)
    keys = list(lighting_key) if isinstance(lighting_key, tuple) else [lighting_key] * len(radii)
    ring = plan_ring(ring_state, centres, radii, eye, settings, tuple(keys))
    next_records = {index: record for index, record in records.items() if index < len(radii)}

    clouds = []
    for index, (centre, radius, distance) in enumerate(zip(centres, radii, distances)):
        distance = float(distance)
        individual = 1.0 - (ring.weight_of(index) if ring is not None else 0.0)
        if radius <= 0.0:
            clouds.append(CloudPlan(index, "empty", distance))
        elif individual <= 0.0:
            clouds.append(CloudPlan(index, "ring", distance))
        elif not visible[index]:
            clouds.append(CloudPlan(index, "culled", distance))
        elif settings.mode == "full":
            clouds.append(CloudPlan(index, "full", distance, full_weight=1.0))
        elif distance < INSIDE_RADII * radius:
            clouds.append(CloudPlan(index, "inside", distance, full_weight=individual))
        else:
            # a cloud fading into or out of the ring is drawn as an impostor: one layer scales exactly
            full = 1.0 if settings.mode == "auto" and individual == 1.0 else 0.0
            if full:
                full = 1.0 - smoothstep(settings.fade_start_radii * radius, settings.fade_end_radii * radius,
                                        distance)
            if full == 1.0:
                clouds.append(CloudPlan(index, "full", distance, full_weight=1.0))
                continue
            pixels = screen_size_px(radius, distance, height, camera.fov_y_deg)
            size = required_size(pixels, settings.impostor_min_size, settings.impostor_max_size)
            record = records.get(index)
            reason = regeneration_reason(record, centre, eye, size, keys[index], settings.tolerance_deg)
            if reason is not None:
                record = ImpostorRecord(tuple(float(v) for v in eye), size, keys[index])
                next_records[index] = record
            kind = "crossfade" if full > 0.0 else "impostor"
            clouds.append(CloudPlan(index, kind, distance, full_weight=full * individual,
                                    impostor_weight=(1.0 - full) * individual, regenerate=reason,
                                    texture_size=record.size))
    drawn = [c.index for c in clouds if c.kind in ("full", "crossfade", "impostor", "inside")]
    draw_order = tuple(sorted(drawn, key=lambda i: -distances[i]))
    inside_size = tuple(max(1, math.ceil(side * settings.inside_resolution_scale)) for side in viewport)
    return FramePlan(tuple(clouds), draw_order, ring, next_records, inside_size)
