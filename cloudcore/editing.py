"""Edits an artist makes, as pure functions from one immutable `Scene` to the next (numpy).

Scenes are immutable, so undo is keeping the previous scene; every edit here
returns a new scene and leaves the old one untouched.  Picking turns a click
into a world-space ray and a point on a ground-parallel plane.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from cloudcore.camera import camera_pose
from cloudcore.scene import Camera, Cloud, Scene

DEFAULT_PARTICLE_RADIUS = 40.0


def pick_ray(camera: Camera, aspect: float, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """(origin, unit direction) through the viewport point (x, y) in [0, 1]^2, y down (screen convention)."""
    pose = camera_pose(camera)
    half_height = math.tan(math.radians(camera.fov_y_deg) / 2.0)
    ndc_x, ndc_y = 2.0 * x - 1.0, 1.0 - 2.0 * y
    direction = pose[:3, :3] @ np.array([ndc_x * half_height * aspect, ndc_y * half_height, -1.0])
    return pose[:3, 3].copy(), direction / np.linalg.norm(direction)


def point_at_altitude(origin, direction, altitude: float) -> np.ndarray | None:
    """Where the ray meets the horizontal plane y = altitude ahead of the eye, or None if it never does."""
    if abs(direction[1]) < 1e-12:
        return None
    distance = (altitude - origin[1]) / direction[1]
    return None if distance <= 0.0 else np.asarray(origin) + distance * np.asarray(direction)


def add_particle(scene: Scene, cloud_index: int, centre, radius: float = DEFAULT_PARTICLE_RADIUS) -> Scene:
    """The scene with one particle added to cloud `cloud_index` (its particle file, if any, is kept in step)."""
    if not radius > 0.0 or not np.all(np.isfinite(centre)):
        raise ValueError(f"a particle needs a finite centre and radius > 0, got {centre}, {radius}")
    cloud = scene.clouds[cloud_index]
    particles = np.vstack([cloud.particles, [*np.asarray(centre, dtype=np.float64), radius]])
    return replace_cloud(scene, cloud_index, dataclasses.replace(cloud, particles=particles))


def add_cloud(scene: Scene, name: str | None = None) -> Scene:
    """The scene with a new empty cloud, named uniquely."""
    taken = {c.name for c in scene.clouds}
    name = name or next(f"cloud{n}" for n in range(len(taken) + 1) if f"cloud{n}" not in taken)
    if name in taken:
        raise ValueError(f"a cloud named {name!r} exists already")
    return dataclasses.replace(scene, clouds=scene.clouds + (Cloud(name),))


def delete_cloud(scene: Scene, cloud_index: int) -> Scene:
    return dataclasses.replace(scene, clouds=scene.clouds[:cloud_index] + scene.clouds[cloud_index + 1:])


def replace_cloud(scene: Scene, cloud_index: int, cloud: Cloud) -> Scene:
    clouds = list(scene.clouds)
    clouds[cloud_index] = cloud
    return dataclasses.replace(scene, clouds=tuple(clouds))


class History:
    """Undo and redo over immutable scenes."""

    def __init__(self, scene: Scene, limit: int = 200):
        self.current, self._undo, self._redo, self._limit = scene, [], [], limit

    def apply(self, scene: Scene) -> None:
        if scene is self.current:
            return
        self._undo = (self._undo + [self.current])[-self._limit:]
        self._redo.clear()
        self.current = scene

    def undo(self) -> bool:
        if not self._undo:
            return False
        self._redo.append(self.current)
        self.current = self._undo.pop()
        return True

    def redo(self) -> bool:
        if not self._redo:
            return False
        self._undo.append(self.current)
        self.current = self._redo.pop()
        return True

    def reset(self, scene: Scene) -> None:
        self.current, self._undo, self._redo = scene, [], []
