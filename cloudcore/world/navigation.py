"""Moving the camera: fly (move along its own axes, turn in place) and orbit its look-at point (numpy)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from cloudcore.model.scene import Camera
from cloudcore.world.camera import camera_pose

#: never look closer than this to straight up or down, where yaw loses its meaning
_PITCH_LIMIT_DEG = 89.0


def moved(camera: Camera, forward: float = 0.0, right: float = 0.0, up: float = 0.0) -> Camera:
    """The camera and its look-at point shifted along its right, up and forward axes (metres)."""
    pose = camera_pose(camera)
    offset = pose[:3, 0] * right + pose[:3, 1] * up - pose[:3, 2] * forward
    return dataclasses.replace(
        camera, position=tuple(np.add(camera.position, offset)), look_at=tuple(np.add(camera.look_at, offset))
    )


def _direction(yaw: float, pitch: float) -> np.ndarray:
    return np.array([math.cos(pitch) * math.sin(yaw), math.sin(pitch), -math.cos(pitch) * math.cos(yaw)])


def _yaw_pitch(vector) -> tuple[float, float]:
    x, y, z = vector
    return math.atan2(x, -z), math.atan2(y, math.hypot(x, z))


def _rotated(offset, yaw_deg: float, pitch_deg: float) -> np.ndarray:
    """`offset` turned by yaw about the vertical and pitch toward it, length kept, pitch clamped."""
    yaw, pitch = _yaw_pitch(offset)
    limit = math.radians(_PITCH_LIMIT_DEG)
    pitch = min(max(pitch + math.radians(pitch_deg), -limit), limit)
    return np.linalg.norm(offset) * _direction(yaw + math.radians(yaw_deg), pitch)


def turned(camera: Camera, yaw_deg: float, pitch_deg: float) -> Camera:
    """The camera turned in place: yaw to the right about the vertical, pitch up."""
    offset = _rotated(np.subtract(camera.look_at, camera.position), yaw_deg, pitch_deg)
    return dataclasses.replace(camera, look_at=tuple(np.add(camera.position, offset)))


def orbited(camera: Camera, yaw_deg: float, pitch_deg: float = 0.0) -> Camera:
    """The camera moved around its look-at point, still looking at it."""
    offset = _rotated(np.subtract(camera.position, camera.look_at), yaw_deg, pitch_deg)
    return dataclasses.replace(camera, position=tuple(np.add(camera.look_at, offset)))
