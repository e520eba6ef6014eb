"""Where the frame plan's impostors and ring panels fall on the screen, for the editor to outline (numpy).

An impostor is a world-space quad through its cloud's centre, facing the eye
it was made from (`cloudcore.lod.impostors.impostor_view`); a ring segment is a
panel of Wang's octagon (`cloudcore.lod.ring.panel_corners`).  Each outline is
that quad clipped to the camera's near plane (ring panels surround the eye,
so some lie partly behind it) and projected to pixels: x right and y down
from the viewport's top-left corner, as the GUI draws.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.lod.impostors import impostor_view
from cloudcore.lod.plan import FramePlan
from cloudcore.lod.plan.unit_plans import TEXTURED
from cloudcore.lod.ring import SEGMENTS, panel_corners
from cloudcore.model.scene import Camera
from cloudcore.world.camera import NEAR_PLANE_M, projection_matrix, view_matrix

#: a quad's corners (lower left, lower right, upper left, upper right) in the order that walks its edges
_AROUND = [0, 1, 3, 2]


@dataclass(frozen=True)
class Outline:
    """A closed polygon in pixels: an impostor (`index` its cloud) or a ring segment (`index` 0-7)."""

    kind: str  # "impostor", "crossfade" or "ring"
    index: int
    points: np.ndarray  # (n, 2), n >= 3


def to_pixels(points, camera: Camera, viewport: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(pixels (N, 2), in front (N,)): world points projected into the viewport; points not in front of
    the near plane get meaningless pixels and False."""
    width, height = viewport
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    eye = (view_matrix(camera) @ np.column_stack([points, np.ones(len(points))]).T).T
    return _eye_to_pixels(eye[:, :3], camera, viewport), eye[:, 2] <= -NEAR_PLANE_M


def screen_polygon(corners, camera: Camera, viewport: tuple[int, int]) -> np.ndarray | None:
    """The world polygon `corners` (n, 3), clipped to the near plane, in pixels; None when wholly behind."""
    corners = np.asarray(corners, dtype=np.float64).reshape(-1, 3)
    eye = (view_matrix(camera) @ np.column_stack([corners, np.ones(len(corners))]).T).T[:, :3]
    clipped = clip_to_near(eye, NEAR_PLANE_M)
    return None if clipped is None else _eye_to_pixels(clipped, camera, viewport)


def clip_to_near(polygon: np.ndarray, near: float) -> np.ndarray | None:
    """The part of an eye-space polygon (n, 3) with z <= -near (Sutherland-Hodgman against one plane)."""
    kept = []
    for start, end in zip(polygon, np.roll(polygon, -1, axis=0)):
        start_in, end_in = start[2] <= -near, end[2] <= -near
        if start_in:
            kept.append(start)
        if start_in != end_in:
            t = (-near - start[2]) / (end[2] - start[2])
            kept.append(start + t * (end - start))
    return np.array(kept) if len(kept) >= 3 else None


def impostor_outlines(plan: FramePlan, camera: Camera, viewport: tuple[int, int]) -> list[Outline]:
    """The quads of the units the plan draws from impostor textures."""
    units, outlines = plan.units, []
    for cloud in plan.of_kind(*TEXTURED):
        record = plan.records[cloud.members]
        corners = impostor_view(units.centres[cloud.index], units.radii[cloud.index], record.eye).corners[_AROUND]
        polygon = screen_polygon(corners, camera, viewport)
        if polygon is not None:
            outlines.append(Outline(cloud.kind, cloud.index, polygon))
    return outlines


def ring_outlines(plan: FramePlan, camera: Camera, viewport: tuple[int, int], elevation_deg: float) -> list[Outline]:
    """The panels of the ring generation drawn with the most weight this frame (none without a ring)."""
    if plan.ring is None or not plan.ring.draws:
        return []
    generation = max(plan.ring.draws, key=lambda draw: draw[1])[0]
    outlines = []
    for segment in range(SEGMENTS):
        polygon = screen_polygon(panel_corners(generation, segment, elevation_deg)[_AROUND], camera, viewport)
        if polygon is not None:
            outlines.append(Outline("ring", segment, polygon))
    return outlines


def _eye_to_pixels(eye: np.ndarray, camera: Camera, viewport: tuple[int, int]) -> np.ndarray:
    width, height = viewport
    projection = projection_matrix(camera.fov_y_deg, width / height)
    depth = np.where(eye[:, 2] < 0.0, -eye[:, 2], np.inf)  # behind the eye: no meaningful pixel
    ndc_x = projection[0, 0] * eye[:, 0] / depth
    ndc_y = projection[1, 1] * eye[:, 1] / depth
    return np.column_stack([(ndc_x + 1.0) * 0.5 * width, (1.0 - ndc_y) * 0.5 * height])
