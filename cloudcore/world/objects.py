"""Opaque objects in the scene: their meshes and where they are at a given time (numpy, trimesh).

An object on a keyframed path moves along the path's Catmull-Rom curve
(`cloudcore.maths.paths.sample`) and faces along its direction of travel, nose
(+x of the mesh) forward and wings level (+y of the mesh up, as near the
world's up as the heading allows).  A static object, or one stopped at the
end of its path, keeps the last heading it had, or the identity.

The built-in primitives are one metre across before `scale`: a box, a sphere
and a small aircraft (fuselage along +x, wings along z).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import trimesh

from cloudcore.maths.paths import sample
from cloudcore.model.scene import SceneObject

_WORLD_UP = np.array([0.0, 1.0, 0.0])
#: seconds: the heading is the chord over this interval, centred on t where the path allows
_HEADING_INTERVAL_S = 0.05


@dataclass(frozen=True)
class ObjectPose:
    """Where one object is: its 4x4 model matrix and its bounding sphere in world space."""

    model: np.ndarray  # model-to-world, scale included
    centre: np.ndarray  # (3,) bounding sphere centre, world
    radius: float


def object_mesh(obj: SceneObject) -> trimesh.Trimesh:
    """The object's mesh in its own frame, before scale: the loaded file or a built-in primitive."""
    if obj.vertices is not None:
        return trimesh.Trimesh(obj.vertices, obj.faces, process=False)
    return _primitive(obj.primitive).copy()


@cache
def _primitive(name: str) -> trimesh.Trimesh:
    if name == "box":
        return trimesh.creation.box((1.0, 1.0, 1.0))
    if name == "sphere":
        return trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    if name == "aircraft":
        return _aircraft()
    raise ValueError(f"no built-in primitive named {name!r}")


def _aircraft() -> trimesh.Trimesh:
    """A 1 m aircraft: fuselage along +x (nose forward), swept-free wings along z, fin and tailplane."""
    fuselage = trimesh.creation.capsule(height=0.8, radius=0.07, count=(12, 12))
    fuselage.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    wings = trimesh.creation.box((0.18, 0.02, 1.0))
    wings.apply_translation((0.02, -0.02, 0.0))
    tailplane = trimesh.creation.box((0.1, 0.015, 0.36))
    tailplane.apply_translation((-0.4, 0.0, 0.0))
    fin = trimesh.creation.box((0.12, 0.18, 0.015))
    fin.apply_translation((-0.4, 0.09, 0.0))
    return trimesh.util.concatenate([fuselage, wings, tailplane, fin])


def mesh_sphere(mesh: trimesh.Trimesh) -> tuple[np.ndarray, float]:
    """(centre, radius) of a sphere around the mesh in its own frame, about its box centre."""
    if not len(mesh.vertices):
        return np.zeros(3), 0.0
    low, high = mesh.bounds
    centre = 0.5 * (low + high)
    return centre, float(np.max(np.linalg.norm(mesh.vertices - centre, axis=1)))


def object_pose(obj: SceneObject, time_s: float, sphere: tuple[np.ndarray, float] | None = None) -> ObjectPose:
    """The object at `time_s` seconds on the scene clock (the clock its path keys are in).

    `sphere` is `mesh_sphere` of its mesh, when the caller keeps it between frames.
    """
    local_centre, local_radius = mesh_sphere(object_mesh(obj)) if sphere is None else sphere
    position, heading = _placement(obj, time_s)
    model = np.eye(4)
    model[:3, :3] = _heading_rotation(heading) * obj.scale
    model[:3, 3] = position
    return ObjectPose(model, model[:3, :3] @ local_centre + position, local_radius * obj.scale)


def _placement(obj: SceneObject, time_s: float) -> tuple[np.ndarray, np.ndarray | None]:
    """(position, unit direction of travel or None) at `time_s`."""
    if obj.path is None:
        return np.asarray(obj.position, dtype=np.float64), None
    keys = obj.path
    start, end = keys[0, 0], keys[-1, 0]
    t = min(max(float(time_s), start), end)
    position = sample(keys, t)  # a path's keys are where the object is; `position` is for static ones
    # a chord inside the keys' time range, so the ends of the path keep their heading
    a = min(max(t - _HEADING_INTERVAL_S / 2, start), max(end - _HEADING_INTERVAL_S, start))
    b = min(a + _HEADING_INTERVAL_S, end)
    chord = sample(keys, b) - sample(keys, a)
    length = np.linalg.norm(chord)
    return position, (chord / length if length > 1e-12 * max(1.0, np.abs(keys[:, 1:]).max()) else None)


def _heading_rotation(heading: np.ndarray | None) -> np.ndarray:
    """Columns: where the mesh's x (nose), y (up) and z axes point in the world."""
    if heading is None:
        return np.eye(3)
    side = np.cross(heading, _WORLD_UP)
    if np.linalg.norm(side) < 1e-9:
        side = np.array([0.0, 0.0, 1.0])  # climbing or diving vertically: any level wing axis
    side /= np.linalg.norm(side)
    up = np.cross(side, heading)
    return np.column_stack([heading, up, side])


def object_poses(objects, time_s: float, spheres=None) -> tuple[ObjectPose, ...]:
    """Every object's pose at `time_s`; `spheres` (`mesh_sphere`, one per object) saves remaking them."""
    spheres = [None] * len(objects) if spheres is None else spheres
    return tuple(object_pose(obj, time_s, sphere) for obj, sphere in zip(objects, spheres))
