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

Objects inside a drawn cloud's bounds split it into layers
(`cloudcore.splitting`); `draw_items` is then the frame's cloud pass far to
near: cloud layers, and the objects between them.  Without objects in clouds
no particle is looked at.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Hashable, Mapping

import numpy as np

from cloudcore.camera import frustum_planes, projection_matrix, spheres_in_frustum, view_matrix
from cloudcore.impostors import (INSIDE_RADII, ImpostorRecord, budgeted_regenerations, detail_size_px,
                                 regeneration_priority, regeneration_reason, required_size, screen_size_px,
                                 translation_error_deg)
from cloudcore.ramps import smoothstep
from cloudcore.ring import RingPlan, RingState, plan_ring
from cloudcore.scene import Camera
from cloudcore.settings import RenderSettings
from cloudcore.splitting import layer_bounds, layer_counts, layer_sort_key, objects_inside

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
    postponed: str | None = None  # why it would be, had the regeneration budget allowed it
    texture_size: int = 0  # side of the impostor texture used
    split_objects: tuple = ()  # indices of the objects inside it, far to near
    splits: tuple = ()  # their distances from the eye: the layers' boundaries
    layer_counts: tuple = ()  # particles per layer, far to near (of the impostor's layers when textured)

    @property
    def layers(self) -> int:
        return len(self.splits) + 1


@dataclass(frozen=True)
class DrawItem:
    """One step of the cloud pass: a layer of a cloud, or an object drawn between layers."""

    kind: str  # "cloud" or "object"
    index: int
    depth: float  # distance from the eye the pass is sorted by, far to near
    layer: int = 0  # of the cloud, 0 the farthest
    near: float = -math.inf  # the layer holds the particles with near < distance from the eye <= far
    far: float = math.inf


@dataclass(frozen=True)
class FramePlan:
    clouds: tuple
    draw_order: tuple  # indices of the clouds drawn individually, far to near
    ring: RingPlan | None
    records: Mapping = field(default_factory=dict)  # the impostor cache after this frame
    inside_size: tuple = (0, 0)  # the screen impostor's texture size (width, height)
    draw_items: tuple = ()  # the cloud pass, far to near (DrawItem)
    objects_with_world: tuple = ()  # visible objects outside split clouds: drawn before the cloud pass

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
            "regenerations_postponed": sum(1 for c in self.clouds if c.postponed),
            "ring_segments_built": int(self.ring is not None and self.ring.state.pending is not None
                                       and self.ring.build_segment in self.ring.state.pending.occupied_segments),
            "ring_panels_drawn": (sum(len(g.occupied_segments) for g, _ in self.ring.draws)
                                  if self.ring is not None else 0),
            "objects_in_clouds": len(self.objects_between_layers),
            "layers_drawn": sum(c.layers for c in self.clouds if c.splits),
            "layers_rebuilt": sum(c.layers for c in self.clouds if c.splits and c.regenerate),
        }

    @property
    def objects_between_layers(self) -> tuple:
        """Objects drawn inside the cloud pass; the rest are drawn with the world."""
        return tuple(item.index for item in self.draw_items if item.kind == "object")


def plan_frame(centres: np.ndarray, radii: np.ndarray, camera: Camera, viewport: tuple[int, int],
               settings: RenderSettings, records: Mapping[int, ImpostorRecord], ring_state: RingState,
               lighting_key: Hashable, objects=(), cloud_particles=None, finest_radii=None) -> FramePlan:
    """Plan one frame; `centres` (N, 3) and `radii` (N,) are the clouds' bounding spheres.

    `lighting_key` identifies what the particles' colours were computed from: one key for
    all clouds, or a tuple with one per cloud (the editor changes one cloud at a time, and
    only that cloud's impostor is stale).  `objects` are the opaque objects' bounding
    spheres this frame (`cloudcore.objects.ObjectPose`); `cloud_particles(i)` gives cloud i's
    particle centres, asked only for clouds with objects inside.  `finest_radii` (N,) are the
    clouds' finest detail in metres (`ParticleShading.finest_radii`), which bounds the impostor
    texture size (`settings.impostor_detail_texels`); None bounds nothing.
    """
    centres, radii = np.asarray(centres, dtype=np.float64).reshape(-1, 3), np.asarray(radii, dtype=np.float64)
    width, height = viewport
    eye = np.asarray(camera.position, dtype=np.float64)
    view_projection = projection_matrix(camera.fov_y_deg, width / height) @ view_matrix(camera)
    planes = frustum_planes(view_projection)
    visible = spheres_in_frustum(planes, centres, radii)
    distances = np.linalg.norm(centres - eye, axis=1)
    keys = list(lighting_key) if isinstance(lighting_key, tuple) else [lighting_key] * len(radii)
    ring = plan_ring(ring_state, centres, radii, eye, settings, tuple(keys))
    next_records = {index: record for index, record in records.items() if index < len(radii)}
    object_centres = np.array([o.centre for o in objects], dtype=np.float64).reshape(-1, 3)
    object_radii = np.array([o.radius for o in objects], dtype=np.float64)
    objects_visible = spheres_in_frustum(planes, object_centres, object_radii)

    def split_at(index: int, from_eye) -> tuple[tuple, tuple]:
        """(objects inside the cloud far to near from `from_eye`, their distances: the layers' boundaries)."""
        inside = objects_inside(centres[index], radii[index], object_centres, object_radii) if (
            settings.split_objects) else ()
        if not len(inside):
            return (), ()
        gaps = np.linalg.norm(object_centres[inside] - np.asarray(from_eye, dtype=np.float64), axis=1)
        order = np.argsort(-gaps, kind="stable")
        return tuple(int(i) for i in inside[order]), tuple(float(g) for g in gaps[order])

    def counts(index: int, from_eye, splits) -> tuple:
        """Particles per layer seen from `from_eye`; the particles are looked at only when there are splits."""
        return layer_counts(cloud_particles(index), from_eye, splits) if splits else (0,)

    finest = np.zeros(len(radii)) if finest_radii is None else np.asarray(finest_radii, dtype=np.float64)
    clouds, wanted = [], []  # wanted: (index, priority) of the impostors past their tolerance
    for index, (centre, radius, distance) in enumerate(zip(centres, radii, distances)):
        distance = float(distance)
        individual = 1.0 - (ring.weight_of(index) if ring is not None else 0.0)
        if radius <= 0.0 or individual <= 0.0 or not visible[index]:
            clouds.append(CloudPlan(index, "empty" if radius <= 0.0 else "ring" if individual <= 0.0 else "culled",
                                    distance))
            continue
        inside, splits = split_at(index, eye)
        # a cloud fading into or out of the ring is drawn as an impostor: one layer scales exactly
        full = 1.0 if settings.mode == "full" or (settings.mode == "auto" and individual == 1.0) else 0.0
        if settings.mode != "full" and distance < INSIDE_RADII * radius:
            clouds.append(CloudPlan(index, "inside", distance, full_weight=individual, split_objects=inside,
                                    splits=splits, layer_counts=counts(index, eye, splits)))
            continue
        if full and settings.mode == "auto":
            full = 1.0 - smoothstep(settings.fade_start_radii * radius, settings.fade_end_radii * radius, distance)
        if full == 1.0:
            clouds.append(CloudPlan(index, "full", distance, full_weight=1.0, split_objects=inside, splits=splits,
                                    layer_counts=counts(index, eye, splits)))
            continue
        pixels = min(screen_size_px(radius, distance, height, camera.fov_y_deg),
                     detail_size_px(radius, distance, finest[index], settings.impostor_detail_texels))
        size = required_size(pixels, settings.impostor_min_size, settings.impostor_max_size)
        record = records.get(index)
        # the layers the impostor's textures would hold now: split where the objects are, seen from its eye
        held_counts = counts(index, record.eye, split_at(index, record.eye)[1]) if (
            record is not None and splits) else None
        reason = regeneration_reason(record, centre, eye, size, keys[index], settings.tolerance_deg, held_counts)
        kind = "crossfade" if full > 0.0 else "impostor"
        clouds.append(CloudPlan(index, kind, distance, full_weight=full * individual,
                                impostor_weight=(1.0 - full) * individual, regenerate=reason,
                                texture_size=size, split_objects=inside, splits=splits))
        if reason is not None:
            ratio = (translation_error_deg(centre, record.eye, eye) / max(settings.tolerance_deg, 1e-300)
                     if record is not None else math.inf)
            wanted.append((index, regeneration_priority(reason, ratio, bool(splits))))
    served = budgeted_regenerations(wanted, settings.regeneration_budget)
    for index, cloud in enumerate(clouds):
        if cloud.kind not in TEXTURED:
            continue
        record = records.get(index)
        if index in served:
            record = next_records[index] = ImpostorRecord(
                tuple(float(v) for v in eye), cloud.texture_size, keys[index], cloud.splits,
                counts(index, eye, cloud.splits))
        regenerate, postponed = (cloud.regenerate, None) if index in served else (None, cloud.regenerate)
        clouds[index] = dataclasses.replace(cloud, regenerate=regenerate, postponed=postponed,
                                            texture_size=record.size,
                                            layer_counts=record.layer_counts if cloud.splits else (0,))
    drawn = [c.index for c in clouds if c.kind in ("full", "crossfade", "impostor", "inside")]
    draw_order = tuple(sorted(drawn, key=lambda i: -distances[i]))
    inside_size = tuple(max(1, math.ceil(side * settings.inside_resolution_scale)) for side in viewport)
    items = _draw_items([clouds[i] for i in draw_order], radii, object_centres, objects_visible, eye)
    between = {item.index for item in items if item.kind == "object"}
    with_world = tuple(i for i in range(len(object_radii)) if objects_visible[i] and i not in between)
    return FramePlan(tuple(clouds), draw_order, ring, next_records, inside_size, items, with_world)


def _draw_items(drawn, radii, object_centres, objects_visible, eye) -> tuple:
    """The cloud pass far to near: each drawn cloud's layers, and each split object once between them."""
    items, objects = [], set()
    for cloud in drawn:
        for layer in range(cloud.layers):
            near, far = layer_bounds(cloud.splits, layer)
            depth = layer_sort_key(near, far, cloud.distance, radii[cloud.index]) if cloud.splits else cloud.distance
            items.append(DrawItem("cloud", cloud.index, depth, layer, near, far))
        objects.update(cloud.split_objects)
    for index in sorted(i for i in objects if objects_visible[i]):
        distance = float(np.linalg.norm(object_centres[index] - eye))
        items.append(DrawItem("object", index, distance, near=distance, far=distance))
    # far to near; at equal depth the layer reaching farther first, then objects before layers
    items.sort(key=lambda item: (-item.depth, -item.far, item.kind != "object"))
    return tuple(items)
