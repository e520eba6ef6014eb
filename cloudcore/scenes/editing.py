"""Edits an artist makes, as pure functions from one immutable `Scene` to the next (numpy).

Scenes are immutable, so undo is keeping the previous scene; every edit here
returns a new scene and leaves the old one untouched.  Picking turns a click
into a world-space ray, then a point on a ground-parallel plane or on the
first particle sphere the ray enters.  A brush stroke scatters particles in a
ball around the point under the mouse, or erases those inside it; a drag moves
a cloud or a particle by where the ray meets a plane through the grabbed
point.  `History` makes a whole stroke or drag (a gesture) one undo step.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from cloudcore.artist.cloudgen import box_fill, preset_cloud
from cloudcore.model.scene import Camera, CameraPath, Cloud, Scene
from cloudcore.world.camera import camera_pose

DEFAULT_PARTICLE_RADIUS = 40.0
_UP = np.array([0.0, 1.0, 0.0])


def pick_ray(camera: Camera, aspect: float, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """(origin, unit direction) through the viewport point (x, y) in [0, 1]^2, y down (screen convention)."""
    pose = camera_pose(camera)
    half_height = math.tan(math.radians(camera.fov_y_deg) / 2.0)
    ndc_x, ndc_y = 2.0 * x - 1.0, 1.0 - 2.0 * y
    direction = pose[:3, :3] @ np.array([ndc_x * half_height * aspect, ndc_y * half_height, -1.0])
    return pose[:3, 3].copy(), direction / np.linalg.norm(direction)


def point_on_plane(origin, direction, point, normal) -> np.ndarray | None:
    """Where the ray meets the plane through `point` with normal `normal` ahead of the eye, or None."""
    origin, direction = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
    normal = np.asarray(normal, dtype=np.float64)
    facing = float(direction @ normal)
    if abs(facing) < 1e-12:
        return None
    distance = float((np.asarray(point, dtype=np.float64) - origin) @ normal) / facing
    return None if distance <= 0.0 else origin + distance * direction


def point_at_altitude(origin, direction, altitude: float) -> np.ndarray | None:
    """Where the ray meets the horizontal plane y = altitude ahead of the eye, or None if it never does."""
    return point_on_plane(origin, direction, (0.0, altitude, 0.0), _UP)


def first_hit(origin, direction, centres, radii) -> tuple[int, float] | None:
    """(index, distance along the unit ray) of the first sphere surface the ray crosses ahead of the eye.

    An eye inside a sphere crosses that sphere's far side; None when the ray misses every sphere.
    """
    origin, direction = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64)
    along = (centres - origin) @ direction  # distance to the point of closest approach
    squared_miss = np.einsum("ij,ij->i", centres - origin, centres - origin) - along * along
    half_chord = np.sqrt(np.maximum(radii * radii - squared_miss, 0.0))
    entry, exit_ = along - half_chord, along + half_chord
    distance = np.where(entry > 0.0, entry, exit_)
    distance[(squared_miss > radii * radii) | (distance <= 0.0)] = np.inf
    if not len(distance) or not np.isfinite(distance.min()):
        return None
    index = int(np.argmin(distance))
    return index, float(distance[index])


def point_on_cloud(cloud: Cloud, origin, direction) -> np.ndarray | None:
    """Where the ray first meets one of the cloud's particle spheres, or None if it misses them all."""
    hit = first_hit(origin, direction, cloud.centres, cloud.radii)
    return None if hit is None else np.asarray(origin, dtype=np.float64) + hit[1] * np.asarray(direction)


def pick_particle(scene: Scene, origin, direction) -> tuple[int, int, np.ndarray] | None:
    """(cloud index, particle index, hit point) of the first particle of any cloud the ray meets, or None."""
    if scene.particle_count == 0:
        return None
    particles = np.concatenate([cloud.particles for cloud in scene.clouds])
    hit = first_hit(origin, direction, particles[:, :3], particles[:, 3])
    if hit is None:
        return None
    starts = np.cumsum([0] + [len(cloud.particles) for cloud in scene.clouds])
    cloud_index = int(np.searchsorted(starts, hit[0], side="right")) - 1
    point = np.asarray(origin, dtype=np.float64) + hit[1] * np.asarray(direction, dtype=np.float64)
    return cloud_index, hit[0] - int(starts[cloud_index]), point


def add_particles(scene: Scene, cloud_index: int, centres, radius: float = DEFAULT_PARTICLE_RADIUS) -> Scene:
    """The scene with particles of one radius added to cloud `cloud_index` (its particle file, if any, is
    kept in step when saved)."""
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    if not radius > 0.0 or not np.all(np.isfinite(centres)):
        raise ValueError(f"a particle needs a finite centre and radius > 0, got {centres.tolist()}, {radius}")
    added = np.column_stack([centres, np.full(len(centres), float(radius))])
    return _with_particles(scene, cloud_index, np.vstack([scene.clouds[cloud_index].particles, added]))


def add_particle(scene: Scene, cloud_index: int, centre, radius: float = DEFAULT_PARTICLE_RADIUS) -> Scene:
    """The scene with one particle added to cloud `cloud_index`."""
    return add_particles(scene, cloud_index, [centre], radius)


def delete_particles(scene: Scene, cloud_index: int, indices) -> Scene:
    """The scene without the cloud's particles at `indices`; the same scene when there are none."""
    indices = np.asarray(indices, dtype=np.int64).reshape(-1)
    if not len(indices):
        return scene
    return _with_particles(scene, cloud_index, np.delete(scene.clouds[cloud_index].particles, indices, axis=0))


def particles_within(cloud: Cloud, centre, radius: float) -> np.ndarray:
    """Indices of the cloud's particles whose centres lie within `radius` of `centre`."""
    offsets = cloud.centres - np.asarray(centre, dtype=np.float64)
    return np.flatnonzero(np.einsum("ij,ij->i", offsets, offsets) <= radius * radius)


def translated(scene: Scene, cloud_index: int, offset, particle: int | None = None) -> Scene:
    """The scene with cloud `cloud_index` (or only its particle `particle`) moved by `offset` metres."""
    offset = np.asarray(offset, dtype=np.float64)
    if offset.shape != (3,) or not np.all(np.isfinite(offset)):
        raise ValueError(f"an offset is a finite 3-vector, got {offset.tolist()}")
    particles = np.array(scene.clouds[cloud_index].particles)
    particles[slice(None) if particle is None else particle, :3] += offset
    return _with_particles(scene, cloud_index, particles)


def with_mean_radius(scene: Scene, cloud_index: int, radius: float) -> Scene:
    """The scene with the cloud's particle radii scaled so that their mean is `radius` (their spread kept)."""
    cloud = scene.clouds[cloud_index]
    if not (math.isfinite(radius) and radius > 0.0):
        raise ValueError(f"a mean particle radius must be finite and > 0, got {radius}")
    if not len(cloud.particles):
        return scene
    particles = np.array(cloud.particles)
    particles[:, 3] *= radius / particles[:, 3].mean()
    return _with_particles(scene, cloud_index, particles)


def _with_particles(scene: Scene, cloud_index: int, particles: np.ndarray) -> Scene:
    cloud = scene.clouds[cloud_index]
    return replace_cloud(scene, cloud_index, dataclasses.replace(cloud, particles=particles))


def scatter_in_ball(rng: np.random.Generator, centre, radius: float, count: int) -> np.ndarray:
    """`count` points (count, 3) uniform in the ball of `radius` around `centre`."""
    directions = rng.normal(size=(count, 3))
    directions /= np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-300)
    # the cube root makes the density uniform in volume, not crowded at the middle
    distances = radius * np.cbrt(rng.uniform(0.0, 1.0, count))
    return np.asarray(centre, dtype=np.float64) + directions * distances[:, None]


class BrushStroke:
    """One press-drag-release of the brush: how many particles are due, and where they go.

    Particles come at `rate` per second of holding, in dabs at most every `interval_s`
    (each dab re-shades the cloud, so a dab a frame would stall the editor); the press
    dabs at once.  A frame slower than two intervals adds no more than two intervals'
    worth, so a stall never dumps a heap of particles in one place.  The same seed and
    the same dabs give the same scatter.
    """

    def __init__(self, seed: int, rate: float, interval_s: float = 0.1):
        if not (math.isfinite(rate) and rate > 0.0):
            raise ValueError(f"a brush rate must be finite and > 0 particles per second, got {rate}")
        self.rng, self.rate, self.interval_s = np.random.default_rng(seed), float(rate), float(interval_s)
        self._waited_s = self.interval_s

    def due(self, seconds: float) -> int:
        """Particles to add now, `seconds` after the previous call (0 between dabs); the first call dabs."""
        if self._waited_s < self.interval_s:
            self._waited_s += seconds
            if self._waited_s < self.interval_s:
                return 0
        count = max(1, round(self.rate * min(self._waited_s, 2.0 * self.interval_s)))
        self._waited_s = 0.0
        return count

    def dab(self, centre, radius: float, count: int) -> np.ndarray:
        """Centres (count, 3) scattered in the brush's ball around `centre`."""
        return scatter_in_ball(self.rng, centre, radius, count)


def drag_plane_normal(camera: Camera, screen: bool) -> np.ndarray:
    """The normal of the plane a drag moves in: horizontal (parallel to the placement plane), or facing
    the camera (`screen`, which moves things up and down too)."""
    return camera_pose(camera)[:3, 2] if screen else _UP.copy()


def drag_offset(origin, direction, grabbed, normal) -> np.ndarray | None:
    """How far the grabbed point has moved: from `grabbed` to where the ray meets the plane through it
    with `normal`; None while the ray misses that plane (toward or beyond its horizon)."""
    point = point_on_plane(origin, direction, grabbed, normal)
    return None if point is None else point - np.asarray(grabbed, dtype=np.float64)


def fill_box(
    scene: Scene,
    cloud_index: int | None,
    centre,
    size,
    particle_radius: float,
    count: int,
    cull_distance: float | None = None,
    seed: int = 0,
) -> tuple[Scene, int]:
    """(scene, index of the filled cloud): Wang's box fill (`cloudgen.box_fill`) of the box `size` around
    `centre`, added to cloud `cloud_index`, or to a new cloud when it is None.

    The cull runs among the new sprites only; the cloud's own particles are left as they are.
    """
    centre, half = np.asarray(centre, dtype=np.float64), 0.5 * np.asarray(size, dtype=np.float64)
    particles = box_fill(centre - half, centre + half, particle_radius, count, cull_distance, seed)
    if cloud_index is None:
        scene, cloud_index = add_cloud(scene), len(scene.clouds)
    return _with_particles(scene, cloud_index, np.vstack([scene.clouds[cloud_index].particles, particles])), cloud_index


def add_preset_cloud(scene: Scene, preset: str, base_centre, scale: float = 1.0, seed: int = 0) -> Scene:
    """The scene with a new cloud of type `preset` (`cloudgen.PRESETS`) whose base is centred on
    `base_centre`, named after the preset."""
    cloud = preset_cloud(preset, _unique_name(scene, preset), base_centre, scale, seed)
    return dataclasses.replace(scene, clouds=scene.clouds + (cloud,))


def add_cloud(scene: Scene, name: str | None = None) -> Scene:
    """The scene with a new empty cloud, named uniquely."""
    name = name or _unique_name(scene, "cloud")
    if name in {c.name for c in scene.clouds}:
        raise ValueError(f"a cloud named {name!r} exists already")
    return dataclasses.replace(scene, clouds=scene.clouds + (Cloud(name),))


def _unique_name(scene: Scene, stem: str) -> str:
    """`stem` followed by the first number no cloud of the scene is named with."""
    taken = {c.name for c in scene.clouds}
    return next(f"{stem}{n}" for n in range(len(taken) + 1) if f"{stem}{n}" not in taken)


def delete_cloud(scene: Scene, cloud_index: int) -> Scene:
    return dataclasses.replace(scene, clouds=scene.clouds[:cloud_index] + scene.clouds[cloud_index + 1 :])


def replace_cloud(scene: Scene, cloud_index: int, cloud: Cloud) -> Scene:
    clouds = list(scene.clouds)
    clouds[cloud_index] = cloud
    return dataclasses.replace(scene, clouds=tuple(clouds))


def with_camera_key(scene: Scene, path_index: int, time_s: float, camera: Camera) -> Scene:
    """The scene with a key of camera path `path_index` at `time_s` looking as `camera` does, among the path's
    keys in time order (a key at that very time is the caller's to refuse: `limits` does)."""
    key = _camera_key(time_s, camera)
    keys = scene.camera_paths[path_index].keys
    at = int(np.searchsorted(keys[:, 0], key[0]))
    return _with_keys(scene, path_index, np.insert(keys, at, key, axis=0))


def with_camera_key_time(scene: Scene, path_index: int, key_index: int, time_s: float) -> Scene:
    """The scene with key `key_index` of camera path `path_index` moved to `time_s`, kept in its place: moved
    past a neighbour, the keys' times no longer increase and `limits` refuses the edit."""
    if not math.isfinite(time_s):
        raise ValueError(f"a key's time must be finite, got {time_s}")
    keys = np.array(scene.camera_paths[path_index].keys)
    keys[key_index, 0] = float(time_s)
    return _with_keys(scene, path_index, keys)


def without_camera_key(scene: Scene, path_index: int, key_index: int) -> Scene:
    """The scene without key `key_index` of camera path `path_index` (a path left with one key `limits`
    refuses)."""
    return _with_keys(scene, path_index, np.delete(scene.camera_paths[path_index].keys, key_index, axis=0))


def with_camera_path(scene: Scene, path: CameraPath) -> Scene:
    """The scene with `path` added after its camera paths."""
    return dataclasses.replace(scene, camera_paths=scene.camera_paths + (path,))


def new_camera_path(scene: Scene, name: str, time_s: float, camera: Camera) -> Scene:
    """The scene with a new camera path `name` from the scene's camera at time 0 to `camera` at `time_s`."""
    start = _camera_key(0.0, scene.camera)
    return with_camera_path(scene, CameraPath(name, np.stack([start, _camera_key(time_s, camera)])))


def _camera_key(time_s: float, camera: Camera) -> np.ndarray:
    key = np.array([time_s, *camera.position, *camera.look_at], dtype=np.float64)
    if not np.all(np.isfinite(key)):
        raise ValueError(f"a key's time and view must be finite, got {key.tolist()}")
    return key


def _with_keys(scene: Scene, path_index: int, keys: np.ndarray) -> Scene:
    paths = list(scene.camera_paths)
    paths[path_index] = dataclasses.replace(paths[path_index], keys=keys)
    return dataclasses.replace(scene, camera_paths=tuple(paths))


class History:
    """Undo and redo over immutable scenes.

    Between `begin_gesture` and `end_gesture` (a brush stroke, a drag) edits replace
    one another and count as one step, undone back to the scene before the gesture.
    """

    def __init__(self, scene: Scene, limit: int = 200):
        self.current, self._undo, self._redo, self._limit = scene, [], [], limit
        self._gesture_start: Scene | None = None

    def apply(self, scene: Scene) -> None:
        if scene is self.current:
            return
        if self._gesture_start is None:
            self._push_undo(self.current)
        self._redo.clear()
        self.current = scene

    @property
    def in_gesture(self) -> bool:
        return self._gesture_start is not None

    def begin_gesture(self) -> None:
        self.end_gesture()
        self._gesture_start = self.current

    def end_gesture(self) -> None:
        start, self._gesture_start = self._gesture_start, None
        if start is not None and start is not self.current:
            self._push_undo(start)

    def _push_undo(self, scene: Scene) -> None:
        self._undo = (self._undo + [scene])[-self._limit :]

    def undo(self) -> bool:
        self.end_gesture()
        if not self._undo:
            return False
        self._redo.append(self.current)
        self.current = self._undo.pop()
        return True

    def redo(self) -> bool:
        self.end_gesture()
        if not self._redo:
            return False
        self._undo.append(self.current)
        self.current = self._redo.pop()
        return True

    def reset(self, scene: Scene) -> None:
        self.current, self._undo, self._redo, self._gesture_start = scene, [], [], None
