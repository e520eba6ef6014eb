"""Dynamic impostors (Schaufler; Harris section 3): their views, their error metrics, when to remake one.

An impostor of a cloud is the cloud rendered alone through a frustum fitted to
its bounding sphere from an eye, drawn afterwards as a quad through the
sphere's centre facing that eye.  It is good while the eye stays close to that
eye: the *translation error* is the angle, seen from the cloud's centre,
between the eye's direction at creation and now; the *resolution error* is a
texture coarser than the cloud's current size on screen asks for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Hashable

import numpy as np

from cloudcore.camera import camera_pose, projection_matrix, view_matrix
from cloudcore.scene import Camera

#: an impostor texture at least this many times finer than needed is remade smaller (saves memory;
#: the factor keeps a cloud at a steady distance from flipping between two sizes)
SHRINK_FACTOR = 4
#: an eye closer to a cloud's centre than this many bounding radii counts as inside it; the margin keeps
#: the quad (half side R d / sqrt(d^2 - R^2)) within 3.2 R
INSIDE_RADII = 1.05


@dataclass(frozen=True)
class ImpostorRecord:
    """What an impostor texture was made from: the eye, the texture side, the lighting, the layers.

    A cloud split around objects (`cloudcore.splitting`) has one texture per layer: `splits`
    are the objects' distances from `eye` when it was made and `layer_counts` its layers'
    particle counts.
    """

    eye: tuple[float, float, float]
    size: int
    lighting_key: Hashable
    splits: tuple[float, ...] = ()
    layer_counts: tuple[int, ...] = (0,)


@dataclass(frozen=True)
class ImpostorView:
    """The frustum that renders an impostor and the world-space quad that shows it."""

    view: np.ndarray
    projection: np.ndarray
    corners: np.ndarray  # (4, 3): lower left, lower right, upper left, upper right


def impostor_view(centre, radius: float, eye) -> ImpostorView:
    """The tight frustum around the sphere (centre, radius) from `eye`, which must lie outside it."""
    centre, eye = np.asarray(centre, dtype=np.float64), np.asarray(eye, dtype=np.float64)
    distance = float(np.linalg.norm(centre - eye))
    if not distance > radius:
        raise ValueError(f"an impostor needs the eye outside the cloud: distance {distance} <= radius {radius}")
    camera = Camera(tuple(eye), tuple(centre), math.degrees(2.0 * math.asin(radius / distance)))
    pose = camera_pose(camera)
    half_side = radius * distance / math.sqrt((distance - radius) * (distance + radius))
    right, up = pose[:3, 0] * half_side, pose[:3, 1] * half_side
    corners = np.array([centre - right - up, centre + right - up, centre - right + up, centre + right + up])
    near = max(distance - radius, distance * 1e-6)
    projection = projection_matrix(camera.fov_y_deg, 1.0, near=near, far=distance + radius)
    return ImpostorView(view_matrix(camera), projection, corners)


def _tangent(radius: float, distance: float) -> float:
    """Half side of the impostor quad of a sphere seen from `distance` (> radius), over that distance."""
    return radius / math.sqrt(max((distance - radius) * (distance + radius), np.finfo(float).tiny))


def screen_size_px(radius: float, distance: float, viewport_height: int, fov_y_deg: float) -> float:
    """Side in pixels of the impostor quad of a sphere seen from `distance` (> radius)."""
    return viewport_height * _tangent(radius, distance) / math.tan(math.radians(fov_y_deg) / 2.0)


def detail_size_px(radius: float, distance: float, finest_radius: float, texels: float) -> float:
    """Texture side that gives a particle of `finest_radius` `texels` texels of radius on the quad.

    A cloud of Gaussian splats holds no detail finer than its smallest splat, so a
    texture finer than this only resamples smooth curves (Nyquist: 3 texels per radius
    sample the kernel's spectrum down to 8-bit quantisation; docs/lod.md).  Inf when
    there is no limit (`texels` 0, or a zero `finest_radius`).
    """
    if not (texels > 0.0 and finest_radius > 0.0):
        return math.inf
    return 2.0 * texels * _tangent(radius, distance) * distance / finest_radius


def required_size(pixels: float, smallest: int, largest: int) -> int:
    """The smallest power of two >= `pixels`, within [smallest, largest]."""
    if not pixels > 1.0:
        return smallest
    return int(min(max(2 ** math.ceil(math.log2(min(pixels, 2.0**30))), smallest), largest))


def translation_error_deg(centre, eye_then, eye_now) -> float:
    """Angle at `centre` between the directions to the two eyes (0 when either coincides with it)."""
    centre = np.asarray(centre, dtype=np.float64)
    a = np.asarray(eye_then, dtype=np.float64) - centre
    b = np.asarray(eye_now, dtype=np.float64) - centre
    # atan2 of |a x b| and a.b stays accurate for tiny angles, where acos of the dot product does not
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b)))


#: the order in which a regeneration budget serves reasons; rank 0 is never postponed: there is
#: no texture to show, or its layers would cut through an object
_REASON_RANK = {"new": 0, "layers": 0, "lights": 1, "resolution": 2, "translation": 3}


def regeneration_priority(reason: str, translation_ratio: float, split: bool) -> tuple[int, float]:
    """Sort key of a wanted regeneration, most urgent first; `translation_ratio` is the translation
    error over the tolerance.  A cloud split around objects is never postponed."""
    return (0 if split else _REASON_RANK[reason], -translation_ratio)


def budgeted_regenerations(wanted, budget: int) -> set:
    """The indices to regenerate now out of `wanted` (index, `regeneration_priority`).

    At most `budget` (0: no limit), yet every one of rank 0; most urgent first, so a
    postponed impostor rises in the queue (its error grows) until it is served.
    """
    if not budget:
        return {index for index, _ in wanted}
    ranked = sorted(wanted, key=lambda w: w[1])
    must = sum(1 for _, priority in ranked if priority[0] == 0)
    return {index for index, _ in ranked[:max(budget, must)]}


def regeneration_reason(record: ImpostorRecord | None, centre, eye, size: int, lighting_key: Hashable,
                        tolerance_deg: float, layer_counts=None) -> str | None:
    """Why the impostor must be remade this frame ("new", "lights", "resolution", "translation",
    "layers"), or None.

    `layer_counts` are the layers' particle counts the objects inside the cloud now give, seen
    from the record's eye (None: the cloud is not split); a change moves particles between
    layer textures, so they are remade.
    """
    if record is None:
        return "new"
    if record.lighting_key != lighting_key:
        return "lights"
    if record.size < size or record.size >= SHRINK_FACTOR * size:
        return "resolution"
    if translation_error_deg(centre, record.eye, eye) > tolerance_deg:
        return "translation"
    if (layer_counts or (0,)) != (record.layer_counts if record.splits else (0,)):
        return "layers"
    return None
