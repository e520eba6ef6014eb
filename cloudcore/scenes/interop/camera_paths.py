"""Camera paths in and out of the files other tools keep them in: glTF camera animation and CSV.

A `CameraPath` key is (t, eye, look-at point).  glTF keeps a camera as a node looking down its -Z axis, +Y up
(cloudview's axes too: metres, right-handed, Y up, so no axes change), turned by a rotation quaternion and
animated by samplers of translation and rotation.  Writing: the eye's translation as a CUBICSPLINE whose
tangents are the Catmull-Rom ones cloudview plays (`cloudcore.maths.paths.sample`), so another tool moves the eye as
cloudview does; the rotation LINEAR (slerped) between keys, exact at them; each key's distance to its look-at
point in the node's `extras` (`cloudview.look_distances`), where a round trip finds it.  Reading: the first
camera node animated directly or through its parents, sampled at every key time of its chain's channels, its
look-at point its forward axis at the `extras`' distance or else at `look_distance_m`.  glTF keeps float32:
a round trip returns the keys rounded to float32, the look-at points within a millionth of their distance.

CSV: a header `t,px,py,pz,lx,ly,lz`, then a key a row, as the scene file's keys.

Reading checks everything a scene would trust (sizes before arrays are made, finite numbers, key times that
increase, a path outside the file's folder); any problem is one `SceneError` naming the file.  Writing is
atomic.
"""

from __future__ import annotations

import base64
import csv
import io
from pathlib import Path

import numpy as np

from cloudcore.model.errors import SceneError
from cloudcore.model.particle_files import atomic_write
from cloudcore.model.scene import Camera, CameraPath
from cloudcore.scenes.limits import MAX_MAGNITUDE, MAX_NAME_LENGTH, camera_path_keys_problem
from cloudcore.world.camera import camera_pose

CSV_COLUMNS = ("t", "px", "py", "pz", "lx", "ly", "lz")
GLTF_SUFFIXES = (".gltf", ".glb")
CAMERA_PATH_SUFFIXES = (".csv", *GLTF_SUFFIXES)
#: keys of one imported path, at most: nearly seven minutes of a key a frame at 25 frames a second (a glTF
#: exporter bakes one a frame).  The scene file holds every key in its TOML: 100,000 keys took 8.9 s to save
#: (tomlkit) and 1.7 s to load, which the editor's autosave would have cost every minute; 10,000 took 0.8 and 0.17 s
MAX_CAMERA_KEYS = 10_000
#: bytes of a camera path file (its buffers included), at most: far more than 10,000 keys of any file need
MAX_CAMERA_FILE_BYTES = 64 * 2**20
#: metres to the look-at point of a glTF camera whose file does not say (no cloudview `extras`)
DEFAULT_LOOK_DISTANCE_M = 1000.0
#: the field of view written for a glTF camera, as cloudview's default camera
DEFAULT_FOV_Y_DEG = Camera().fov_y_deg

_FLOAT = 5126  # glTF's componentType of float32
_COMPONENTS = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}


def read_camera_path(path, name: str | None = None, look_distance_m: float = DEFAULT_LOOK_DISTANCE_M) -> CameraPath:
    """The camera path in the .csv, .gltf or .glb file at `path`, named `name` (else the file's stem).
    SceneError, naming the file, for anything that cannot be imported."""
    path = Path(path)
    source = str(path)
    if path.suffix.lower() not in CAMERA_PATH_SUFFIXES:
        raise SceneError(source, "(file)", f"a camera path is read from {', '.join(CAMERA_PATH_SUFFIXES)} files")
    data = _read_bytes(path)
    if path.suffix.lower() == ".csv":
        keys = _csv_keys(source, data)
    else:
        if not (np.isfinite(look_distance_m) and 0.0 < look_distance_m <= MAX_MAGNITUDE):
            raise SceneError(
                source, "--look-distance", f"must be within (0, {MAX_MAGNITUDE:g}] m, got {look_distance_m}"
            )
        keys = _GltfReader(source, path.parent, data).camera_keys(look_distance_m)
    name = (name or path.stem)[:MAX_NAME_LENGTH]
    problem = camera_path_keys_problem(keys)
    if problem is not None:
        raise SceneError(source, "keys", problem)
    return CameraPath(name, keys)


def write_camera_path(path, camera_path: CameraPath, fov_y_deg: float = DEFAULT_FOV_Y_DEG) -> None:
    """Write `camera_path` to the .csv, .gltf (one file, its buffer inline) or .glb file at `path`, atomically."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".csv":
        data = _csv_text(camera_path.keys).encode("utf-8")
    elif suffix in GLTF_SUFFIXES:
        data = _gltf_bytes(camera_path, fov_y_deg, binary=suffix == ".glb")
    else:
        raise SceneError(str(path), "(file)", f"a camera path is written to {', '.join(CAMERA_PATH_SUFFIXES)} files")
    atomic_write(path, lambda f: f.write(data))


def _read_bytes(path: Path) -> bytes:
    source = str(path)
    if not path.exists():
        raise SceneError(source, "(file)", "no such file")
    if not path.is_file():
        raise SceneError(source, "(file)", "not a regular file (a folder, a pipe or a device)")
    size = path.stat().st_size
    if size > MAX_CAMERA_FILE_BYTES:
        raise SceneError(source, "(file)", f"{size:,} bytes, at most {MAX_CAMERA_FILE_BYTES:,}")
    try:
        return path.read_bytes()
    except OSError as error:
        raise SceneError(source, "(file)", f"cannot read: {error}") from None


def _checked_numbers(source: str, field: str, values: np.ndarray) -> np.ndarray:
    bad = ~np.isfinite(values)
    if bad.any():
        raise SceneError(source, field, f"numbers must be finite, got {values[bad][0]}")
    if values.size and np.abs(values).max() > MAX_MAGNITUDE:
        raise SceneError(source, field, f"numbers must be within +-{MAX_MAGNITUDE:g}, got {np.abs(values).max():.3g}")
    return values


# ---------------------------------------------------------------- CSV


def _csv_keys(source: str, data: bytes) -> np.ndarray:
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise SceneError(source, "(file)", f"not UTF-8 text: {error}") from None
    try:
        rows = [row for row in csv.reader(io.StringIO(text)) if row and any(cell.strip() for cell in row)]
    except csv.Error as error:  # a field past the csv module's 131,072 characters, a NUL
        raise SceneError(source, "(file)", f"not a readable CSV: {error}") from None
    if not rows or tuple(cell.strip() for cell in rows[0]) != CSV_COLUMNS:
        found = ",".join(rows[0])[:80] if rows else "nothing"
        raise SceneError(source, "header", f"expected the columns {','.join(CSV_COLUMNS)}, got {found!r}")
    if len(rows) - 1 > MAX_CAMERA_KEYS:
        raise SceneError(source, "keys", f"{len(rows) - 1:,} keys, at most {MAX_CAMERA_KEYS:,}")
    keys = np.empty((len(rows) - 1, len(CSV_COLUMNS)))
    for index, row in enumerate(rows[1:]):
        if len(row) != len(CSV_COLUMNS):
            raise SceneError(source, f"row {index + 2}", f"expected {len(CSV_COLUMNS)} numbers, got {len(row)}")
        try:
            keys[index] = [float(cell) for cell in row]
        except ValueError:
            raise SceneError(source, f"row {index + 2}", f"expected numbers, got {','.join(row)[:80]!r}") from None
    return _checked_numbers(source, "keys", keys)


def _csv_text(keys: np.ndarray) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    writer.writerows([repr(float(value)) for value in row] for row in keys)
    return out.getvalue()


# ---------------------------------------------------------------- glTF: orientation


def rotation_quaternion(eye, look_at) -> np.ndarray:
    """(x, y, z, w), unit: the rotation turning glTF's camera (looking down -Z, +Y up) to look from `eye` at
    `look_at` as cloudview's camera does (no roll: its right axis horizontal)."""
    matrix = camera_pose(Camera(tuple(eye), tuple(look_at)))[:3, :3]
    return _matrix_to_quaternion(matrix)


def _matrix_to_quaternion(m: np.ndarray) -> np.ndarray:
    """(x, y, z, w) of a rotation matrix (Shepperd's method: the largest of the four components first)."""
    trace = np.trace(m)
    candidates = [trace, m[0, 0], m[1, 1], m[2, 2]]
    largest = int(np.argmax(candidates))
    if largest == 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
    elif largest == 1:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif largest == 2:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s]
    q = np.array(q)
    return q / np.linalg.norm(q)


def quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of unit quaternions (n, 4) as (x, y, z, w)."""
    x, y, z, w = np.moveaxis(np.asarray(q, dtype=np.float64).reshape(-1, 4), 1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=1,
    )


def _slerp(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Spherical interpolation of unit quaternions (n, 4) by `s` (n,), the shorter way round."""
    dot = np.einsum("ij,ij->i", a, b)
    b = np.where(dot[:, None] < 0.0, -b, b)
    dot = np.abs(dot)
    angle = np.arccos(np.clip(dot, -1.0, 1.0))
    near = angle < 1e-6  # nearly equal: the straight line is as good and does not divide by ~0
    sin = np.where(near, 1.0, np.sin(angle))
    wa = np.where(near, 1.0 - s, np.sin((1.0 - s) * angle) / sin)
    wb = np.where(near, s, np.sin(s * angle) / sin)
    out = wa[:, None] * a + wb[:, None] * b
    return out / np.linalg.norm(out, axis=1, keepdims=True)


# ---------------------------------------------------------------- glTF: writing


def _gltf_bytes(camera_path: CameraPath, fov_y_deg: float, binary: bool) -> bytes:
    import pygltflib as gl

    keys = camera_path.keys
    times, eyes, looks = keys[:, 0], keys[:, 1:4], keys[:, 4:7]
    rotations = np.array([rotation_quaternion(eye, look) for eye, look in zip(eyes, looks)])
    # the Catmull-Rom tangents of `cloudcore.maths.paths.sample`, per second: in and out alike (the path is C1)
    after, before = np.minimum(np.arange(len(keys)) + 1, len(keys) - 1), np.maximum(np.arange(len(keys)) - 1, 0)
    tangents = (eyes[after] - eyes[before]) / (times[after] - times[before])[:, None]
    translation = np.stack([tangents, eyes, tangents], axis=1).reshape(-1, 3)  # glTF's (in, value, out)
    arrays = [times.astype(np.float32), translation.astype(np.float32), rotations.astype(np.float32)]
    blob = b"".join(array.tobytes() for array in arrays)
    views, accessors, offset = [], [], 0
    for array, kind in zip(arrays, ("SCALAR", "VEC3", "VEC4")):
        views.append(gl.BufferView(buffer=0, byteOffset=offset, byteLength=array.nbytes))
        accessor = gl.Accessor(bufferView=len(views) - 1, componentType=_FLOAT, count=len(array), type=kind)
        if kind == "SCALAR":  # an animation's input must give its range
            accessor.min, accessor.max = [float(array.min())], [float(array.max())]
        accessors.append(accessor)
        offset += array.nbytes
    look_distances = np.linalg.norm(looks - eyes, axis=1)
    node = gl.Node(
        name=camera_path.name,
        camera=0,
        translation=eyes[0].tolist(),
        rotation=rotations[0].tolist(),
        extras={"cloudview": {"look_distances": look_distances.tolist()}},
    )
    document = gl.GLTF2(
        asset=gl.Asset(version="2.0", generator="cloudview"),
        scene=0,
        scenes=[gl.Scene(nodes=[0])],
        nodes=[node],
        cameras=[
            gl.Camera(
                type="perspective",
                perspective=gl.Perspective(yfov=float(np.radians(fov_y_deg)), znear=1.0, aspectRatio=None),
            )
        ],
        animations=[
            gl.Animation(
                name=camera_path.name,
                samplers=[
                    gl.AnimationSampler(input=0, output=1, interpolation="CUBICSPLINE"),
                    gl.AnimationSampler(input=0, output=2, interpolation="LINEAR"),
                ],
                channels=[
                    gl.AnimationChannel(sampler=0, target=gl.AnimationChannelTarget(node=0, path="translation")),
                    gl.AnimationChannel(sampler=1, target=gl.AnimationChannelTarget(node=0, path="rotation")),
                ],
            )
        ],
        accessors=accessors,
        bufferViews=views,
        buffers=[gl.Buffer(byteLength=len(blob))],
    )
    if binary:
        document.set_binary_blob(blob)
        return b"".join(document.save_to_bytes())
    document.buffers[0].uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")
    return document.gltf_to_json().encode("utf-8")


# ---------------------------------------------------------------- glTF: reading


class _GltfReader:
    """One glTF document's camera animation, every index and size checked before it is used."""

    def __init__(self, source: str, folder: Path, data: bytes):
        import pygltflib as gl

        self.source, self.folder = source, folder
        try:
            self.document = gl.GLTF2.load_from_bytes(data) if data[:4] == b"glTF" else gl.GLTF2.gltf_from_json(data)
        except Exception as error:  # pygltflib raises what json, struct and its dataclasses raise on a bad file
            self.fail("(file)", f"not a readable glTF file (truncated or corrupt?): {str(error)[:200]}")
        if self.document is None:
            self.fail("(file)", "not a readable glTF file (truncated or corrupt?)")
        self._buffers: dict[int, bytes] = {}

    def fail(self, field: str, problem: str):
        raise SceneError(self.source, field, problem)

    def camera_keys(self, look_distance_m: float) -> np.ndarray:
        try:
            return self._camera_keys(look_distance_m)
        except SceneError:
            raise
        except (TypeError, ValueError, KeyError, IndexError, AttributeError) as error:  # a field of the wrong type
            self.fail("(file)", f"malformed glTF: {type(error).__name__}: {str(error)[:200]}")

    def _camera_keys(self, look_distance_m: float) -> np.ndarray:
        nodes = self._list("nodes")
        parents = self._parents(nodes)
        channels = [
            (animation_index, channel)
            for animation_index, animation in enumerate(self._list("animations"))
            for channel in animation.channels or []
            if channel.target is not None and channel.target.path in ("translation", "rotation")
        ]
        for index, node in enumerate(nodes):
            if node.camera is None:
                continue
            chain = [index]
            while parents.get(chain[-1]) is not None:
                chain.append(parents[chain[-1]])
            moving = [(a, c) for a, c in channels if c.target.node in chain]
            if moving:
                return self._sampled_keys(nodes, chain, moving, index, look_distance_m)
        self.fail("animations", "no camera node is animated (by translation or rotation, its own or a parent's)")

    def _list(self, name: str) -> list:
        value = getattr(self.document, name, None) or []
        if not isinstance(value, list):
            self.fail(name, f"expected an array, got {type(value).__name__}")
        return value

    def _parents(self, nodes: list) -> dict[int, int]:
        parents = {}
        for index, node in enumerate(nodes):
            for child in node.children or []:
                if not (isinstance(child, int) and 0 <= child < len(nodes)) or child in parents or child == index:
                    self.fail(f"nodes[{index}].children", f"child {child!r} is not a node of its own, once")
                parents[child] = index
        for start in parents:  # a cycle would make the chain up from a node endless
            seen, node = set(), start
            while node in parents:
                if node in seen:
                    self.fail("nodes", "the node hierarchy has a cycle")
                seen.add(node)
                node = parents[node]
        return parents

    def _sampled_keys(self, nodes, chain, moving, camera_index: int, look_distance_m: float) -> np.ndarray:
        samplers = {}
        for animation_index, channel in moving:
            animation = self.document.animations[animation_index]
            field = f"animations[{animation_index}]"
            if not (isinstance(channel.sampler, int) and 0 <= channel.sampler < len(animation.samplers or [])):
                self.fail(field, f"channel's sampler {channel.sampler!r} is not one of the animation's")
            sampler = animation.samplers[channel.sampler]
            times = self._accessor(sampler.input, "SCALAR", f"{field}.samplers[{channel.sampler}].input")[:, 0]
            if np.any(np.diff(times) <= 0.0):
                self.fail(f"{field}.samplers[{channel.sampler}].input", "key times must increase strictly")
            width = 3 if channel.target.path == "translation" else 4
            values = self._accessor(sampler.output, "VEC3" if width == 3 else "VEC4", f"{field}.output")
            interpolation = sampler.interpolation or "LINEAR"
            if interpolation == "CUBICSPLINE":
                values = values[1::3] if len(values) == 3 * len(times) else values[:0]
            elif interpolation not in ("LINEAR", "STEP"):
                self.fail(f"{field}.samplers[{channel.sampler}]", f"unknown interpolation {interpolation!r}")
            if len(values) != len(times):
                self.fail(f"{field}.output", f"{len(values)} values for {len(times)} key times")
            if width == 4:
                norms = np.linalg.norm(values, axis=1)
                if not np.all(norms > 1e-6):
                    self.fail(f"{field}.output", "a rotation quaternion of length 0")
                values = values / norms[:, None]
            samplers[(channel.target.node, channel.target.path)] = (times, values, interpolation)
        all_times = np.unique(np.concatenate([times for times, _, _ in samplers.values()]))
        if len(all_times) > MAX_CAMERA_KEYS:
            self.fail("animations", f"{len(all_times):,} key times, at most {MAX_CAMERA_KEYS:,}")
        world = np.broadcast_to(np.eye(4), (len(all_times), 4, 4))
        for node_index in reversed(chain):  # the root's transform first
            world = world @ self._local_matrices(nodes[node_index], node_index, samplers, all_times)
        eyes = world[:, :3, 3]
        forward = -world[:, :3, 2]
        lengths = np.linalg.norm(forward, axis=1)
        if not np.all(lengths > 1e-9):
            self.fail("nodes", "the camera's transform is singular (scaled to nothing)")
        distances = self._look_distances(nodes[camera_index], len(all_times), look_distance_m)
        looks = eyes + forward / lengths[:, None] * distances[:, None]
        return np.column_stack([all_times, eyes, looks])

    def _look_distances(self, node, count: int, default_m: float) -> np.ndarray:
        """Each key's distance to its look-at point: cloudview's `extras` where they hold one a key, else
        `default_m`."""
        extras = node.extras if isinstance(node.extras, dict) else {}
        cloudview = extras.get("cloudview")
        stored = cloudview.get("look_distances") if isinstance(cloudview, dict) else None
        if isinstance(stored, list) and len(stored) == count:
            try:
                distances = np.array(stored, dtype=np.float64)
            except (TypeError, ValueError):
                distances = np.zeros(0)
            if distances.shape == (count,) and np.all(np.isfinite(distances) & (distances > 0.0)):
                return distances
        return np.full(count, default_m)

    def _local_matrices(self, node, index: int, samplers: dict, times: np.ndarray) -> np.ndarray:
        """(n, 4, 4) the node's local transform at `times`: its TRS (or matrix), animated where a sampler says."""
        field = f"nodes[{index}]"
        if node.matrix is not None:
            matrix = _checked_numbers(self.source, field, np.array(node.matrix, dtype=np.float64))
            if matrix.shape != (16,):
                self.fail(field, "its matrix is not 16 numbers")
            static = matrix.reshape(4, 4).T  # glTF's matrices are column-major
            if any((index, path) in samplers for path in ("translation", "rotation")):
                self.fail(field, "a node animated by translation or rotation must not have a matrix")
            return np.broadcast_to(static, (len(times), 4, 4))
        translation = self._static(node.translation, (0.0, 0.0, 0.0), field + ".translation")
        rotation = self._static(node.rotation, (0.0, 0.0, 0.0, 1.0), field + ".rotation")
        scale = self._static(node.scale, (1.0, 1.0, 1.0), field + ".scale")
        if np.linalg.norm(rotation) < 1e-6:
            self.fail(field + ".rotation", "a rotation quaternion of length 0")
        translations = np.broadcast_to(translation, (len(times), 3))
        rotations = np.broadcast_to(rotation / np.linalg.norm(rotation), (len(times), 4))
        if (index, "translation") in samplers:
            translations = _sampled(*samplers[(index, "translation")], times)
        if (index, "rotation") in samplers:
            rotations = _sampled(*samplers[(index, "rotation")], times, rotation=True)
        matrices = np.zeros((len(times), 4, 4))
        matrices[:, :3, :3] = quaternion_matrices(rotations) * scale[None, None, :]
        matrices[:, :3, 3] = translations
        matrices[:, 3, 3] = 1.0
        return matrices

    def _static(self, value, default, field: str) -> np.ndarray:
        array = np.array(default if value is None else value, dtype=np.float64)
        if array.shape != (len(default),):
            self.fail(field, f"expected {len(default)} numbers, got {value!r}"[:200])
        return _checked_numbers(self.source, field, array)

    def _accessor(self, index, kind: str, field: str) -> np.ndarray:
        """(count, components) float64 of a float accessor, its bounds within its buffer checked first."""
        accessors = self._list("accessors")
        if not (isinstance(index, int) and 0 <= index < len(accessors)):
            self.fail(field, f"accessor {index!r} is not one of the file's {len(accessors)}")
        accessor = accessors[index]
        field = f"accessors[{index}]"
        if accessor.type != kind or accessor.componentType != _FLOAT or accessor.sparse is not None:
            self.fail(field, f"expected {kind} float32 (not sparse), got {accessor.type} of {accessor.componentType}")
        count, components = accessor.count, _COMPONENTS[kind]
        if not (isinstance(count, int) and 1 <= count <= 4 * MAX_CAMERA_KEYS):
            self.fail(field, f"a count of {count!r}, expected 1 to {4 * MAX_CAMERA_KEYS:,}")
        views = self._list("bufferViews")
        if not (isinstance(accessor.bufferView, int) and 0 <= accessor.bufferView < len(views)):
            self.fail(field, f"buffer view {accessor.bufferView!r} is not one of the file's")
        view = views[accessor.bufferView]
        stride = view.byteStride or 4 * components
        offset = (view.byteOffset or 0) + (accessor.byteOffset or 0)
        needed = (accessor.byteOffset or 0) + stride * (count - 1) + 4 * components
        if stride < 4 * components or needed > (view.byteLength or 0):
            self.fail(field, f"reaches past its buffer view ({needed:,} bytes of {view.byteLength!r})")
        data = self._buffer(view.buffer)
        if (view.byteOffset or 0) + view.byteLength > len(data):
            self.fail(f"bufferViews[{accessor.bufferView}]", f"reaches past its buffer's {len(data):,} bytes")
        values = np.ndarray((count, components), dtype="<f4", buffer=data, offset=offset, strides=(stride, 4))
        return _checked_numbers(self.source, field, values.astype(np.float64))

    def _buffer(self, index) -> bytes:
        buffers = self._list("buffers")
        if not (isinstance(index, int) and 0 <= index < len(buffers)):
            self.fail("bufferViews", f"buffer {index!r} is not one of the file's")
        if index not in self._buffers:
            self._buffers[index] = self._buffer_bytes(index, buffers[index])
        return self._buffers[index]

    def _buffer_bytes(self, index: int, buffer) -> bytes:
        field = f"buffers[{index}]"
        uri = buffer.uri
        if uri is None:  # a .glb's binary chunk
            blob = self.document.binary_blob()
            if blob is None:
                self.fail(field, "has no uri and the file no binary chunk")
            return blob
        if not isinstance(uri, str):
            self.fail(field, f"its uri is not a string: {uri!r}"[:200])
        if uri.startswith("data:"):
            if len(uri) > 2 * MAX_CAMERA_FILE_BYTES:
                self.fail(field, "its data uri is too large")
            try:
                return base64.b64decode(uri.partition(",")[2], validate=True)
            except ValueError as error:
                self.fail(field, f"its data uri is not base64: {error}")
        file = (self.folder / uri).resolve()
        if Path(uri).is_absolute() or "://" in uri or not file.is_relative_to(self.folder.resolve()):
            self.fail(field, f"its uri {uri[:100]!r} leads outside the glTF file's folder")
        return _read_bytes(file)


def _sampled(times: np.ndarray, values: np.ndarray, interpolation: str, at: np.ndarray, rotation=False) -> np.ndarray:
    """A sampler's values at the times `at`: held past its ends, the previous key's for STEP, else linear
    (slerped for a rotation) between keys (a CUBICSPLINE's between its keys too: only keys are sampled)."""
    after = np.clip(np.searchsorted(times, at, side="right"), 1, len(times) - 1) if len(times) > 1 else None
    if after is None:
        return np.broadcast_to(values[0], (len(at), values.shape[1])).copy()
    before = after - 1
    s = np.clip((at - times[before]) / (times[after] - times[before]), 0.0, 1.0)
    if interpolation == "STEP":
        s = np.where(s >= 1.0, 1.0, 0.0)
    if rotation:
        return _slerp(values[before], values[after], s)
    return values[before] * (1.0 - s[:, None]) + values[after] * s[:, None]
