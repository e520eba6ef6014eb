"""View and projection matrices of a `cloudcore.model.scene.Camera`, and frustum culling (numpy).

OpenGL conventions: right-handed eye space looking down -z with y up, clip
space depth in [-1, 1].  `projection_matrix` is the same matrix pyrender builds
for a `PerspectiveCamera` with a far plane, so depths written by pyrender's
world pass and by our own passes compare correctly.
"""

from __future__ import annotations

import math

import numpy as np

from cloudcore.model.scene import Camera

#: metres; 1 m near and 100 km far keep 24-bit depth resolution near 0.5 m at 3 km.
NEAR_PLANE_M = 1.0
FAR_PLANE_M = 1.0e5


def camera_pose(camera: Camera) -> np.ndarray:
    """Camera-to-world 4x4: columns are the camera's right, up and back axes and its position.

    Written out in scalars: every impostor regeneration makes a pose, and numpy's `cross` and `norm` on
    3-vectors cost 0.25 ms of each (40 regenerations a frame, docs/journal.md, "A frame's regenerations together").
    """
    ex, ey, ez = (float(value) for value in camera.position)
    fx, fy, fz = (float(target) - origin for target, origin in zip(camera.look_at, (ex, ey, ez)))
    # hypot, not the root of the squares: a look-at point 1e-300 m away squares to 0
    length = math.hypot(fx, fy, fz)
    if length == 0.0:
        # the eye at its own look-at point (a camera path whose two keys swap eye and target, halfway): the
        # loader refuses it in a key; between keys the view looks down -z
        fx, fy, fz, length = 0.0, 0.0, -1.0, 1.0
    fx, fy, fz = fx / length, fy / length, fz / length
    # right = forward x world up (0, 1, 0), horizontal
    rx, rz = -fz, fx
    horizontal = math.hypot(rx, rz)
    if horizontal < 1e-9:
        # looking straight up or down: any horizontal right axis will do; take east
        rx, rz, horizontal = 1.0, 0.0, 1.0
    rx, rz = rx / horizontal, rz / horizontal
    # up = right x forward
    ux, uy, uz = -rz * fy, rz * fx - rx * fz, rx * fy
    return np.array([[rx, ux, -fx, ex], [0.0, uy, -fy, ey], [rz, uz, -fz, ez], [0.0, 0.0, 0.0, 1.0]])


def view_matrix(camera: Camera) -> np.ndarray:
    """World-to-eye 4x4 (the inverse of `camera_pose`, computed without a general inverse)."""
    return pose_to_view(camera_pose(camera))


def view_rotation(view: np.ndarray) -> np.ndarray:
    """The view matrix without its translation: for points given relative to its eye (float32 on the GPU keeps
    them their size far from the origin)."""
    rotation = np.array(view, dtype=np.float64)
    rotation[:3, 3] = 0.0
    return rotation


def pose_to_view(pose: np.ndarray) -> np.ndarray:
    """The view matrix of a camera-to-world `pose` of orthonormal axes: its inverse."""
    rotation = pose[:3, :3].T
    view = np.eye(4)
    view[:3, :3] = rotation
    view[:3, 3] = -rotation @ pose[:3, 3]
    return view


def projection_matrix(
    fov_y_deg: float, aspect: float, near: float = NEAR_PLANE_M, far: float = FAR_PLANE_M
) -> np.ndarray:
    """OpenGL perspective projection, vertical field of view in degrees, aspect = width / height."""
    focal = 1.0 / np.tan(0.5 * np.radians(fov_y_deg))
    projection = np.zeros((4, 4))
    projection[0, 0] = focal / aspect
    projection[1, 1] = focal
    projection[2, 2] = (far + near) / (near - far)
    projection[2, 3] = 2.0 * far * near / (near - far)
    projection[3, 2] = -1.0
    return projection


def pixel_rays(camera: Camera, width: int, height: int) -> np.ndarray:
    """Unit world directions (height, width, 3), top row first, through each pixel's centre.

    The rays of `projection_matrix` and `camera_pose`: what a fragment at the pixel centre sees, so
    a path tracer given the same pose and field of view lines up with the GL frame pixel for pixel.
    """
    pose = camera_pose(camera)
    half_height = np.tan(0.5 * np.radians(camera.fov_y_deg))
    x = ((np.arange(width) + 0.5) / width * 2.0 - 1.0) * half_height * width / height
    y = (1.0 - (np.arange(height) + 0.5) / height * 2.0) * half_height
    right, up, back = pose[:3, 0], pose[:3, 1], pose[:3, 2]
    rays = x[None, :, None] * right + y[:, None, None] * up - back
    return rays / np.linalg.norm(rays, axis=2, keepdims=True)


def frustum_planes(view_projection: np.ndarray) -> np.ndarray:
    """The six planes (a, b, c, d) of the clip volume, normals inward and unit length.

    Gribb and Hartmann: a point x is inside plane i when planes[i] . (x, 1) >= 0.
    """
    rows = view_projection
    planes = np.array(
        [
            rows[3] + rows[0],
            rows[3] - rows[0],
            rows[3] + rows[1],
            rows[3] - rows[1],
            rows[3] + rows[2],
            rows[3] - rows[2],
        ]
    )
    return planes / np.linalg.norm(planes[:, :3], axis=1, keepdims=True)


def points_in_eye_space(points: np.ndarray, view: np.ndarray) -> np.ndarray:
    """(N, 3): `points` (N, 3) in the eye space of the view matrix `view`."""
    # the rotation transposed into a contiguous copy: numpy multiplies by it several times faster, and the planner
    # transforms every near cloud's splats every frame
    return points @ np.ascontiguousarray(view[:3, :3].T) + view[:3, 3]


def spheres_in_frustum(planes: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Boolean (N,): which spheres are at least partly inside the frustum (conservative)."""
    return np.all(_plane_distances(planes, centres) >= -np.asarray(radii, dtype=np.float64), axis=0)


def spheres_within_frustum(planes: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Boolean (N,): which spheres lie wholly inside the frustum."""
    return np.all(_plane_distances(planes, centres) >= np.asarray(radii, dtype=np.float64), axis=0)


def _plane_distances(planes: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(6, N): each centre's signed distance from each plane, positive inside."""
    # plane by plane, each a contiguous row: numpy reduces rows of six an order of magnitude more slowly, and every
    # draw near the eye tests its splats
    return planes[:, :3] @ np.asarray(centres, dtype=np.float64).reshape(-1, 3).T + planes[:, 3:]


def screen_box(centre, radius: float, camera: Camera, viewport: tuple[int, int]) -> tuple[slice, slice] | None:
    """(rows, columns) of the image, top row first, covering a sphere's image; None when it is behind the eye.

    The box is that of the sphere's tangent cone's image, bounded by the
    distance to its centre (conservative, and exact enough to crop around an
    object's silhouette).
    """
    width, height = viewport
    eye_space = view_matrix(camera) @ np.append(np.asarray(centre, dtype=np.float64), 1.0)
    depth = -eye_space[2]
    if depth <= radius:
        return None
    projection = projection_matrix(camera.fov_y_deg, width / height)
    focal_x, focal_y = projection[0, 0], projection[1, 1]
    spread = radius / np.sqrt(depth * depth - radius * radius)
    x = (eye_space[0] / depth * focal_x + np.array([-1.0, 1.0]) * spread * focal_x + 1.0) * 0.5 * width
    y = (1.0 - (eye_space[1] / depth * focal_y + np.array([1.0, -1.0]) * spread * focal_y)) * 0.5 * height
    columns = np.clip(np.floor(x).astype(int) + [0, 1], 0, width)
    rows = np.clip(np.floor(y).astype(int) + [0, 1], 0, height)
    if columns[0] >= columns[1] or rows[0] >= rows[1]:
        return None
    return slice(*rows), slice(*columns)
