"""Camera paths in and out: glTF camera animation and CSV through `cloudview import` / `export`, read back equal,
the orientation converted both ways, another tool's camera hierarchy read, and each bad file refused."""

import base64
import json

import numpy as np
import pygltflib
import pytest

from cloudcore.cli import main
from cloudcore.maths.paths import sample
from cloudcore.model.scene import NEW_SCENE_SHADING, Camera, CameraPath, Scene
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.interop.camera_paths import (
    DEFAULT_LOOK_DISTANCE_M,
    MAX_CAMERA_KEYS,
    quaternion_matrices,
    read_camera_path,
    rotation_quaternion,
    write_camera_path,
)
from cloudcore.world.camera import camera_pose

#: keys with uneven times, a look straight down and one backwards along +z
KEYS = np.array(
    [
        [0.0, 0.0, 700.0, 3000.0, -300.0, 1000.0, 2000.0],
        [2.5, 100.0, 800.0, 2500.0, 100.0, 0.0, 2500.0],
        [7.0, 400.0, 900.0, 1000.0, 400.0, 900.0, 1800.0],
        [12.25, 1000.1, 1500.3, -200.7, -900.0, 400.0, -3000.0],
    ]
)
PATH = CameraPath("tour", KEYS)


def float32(values):
    return np.asarray(values, dtype=np.float32).astype(np.float64)


def test_csv_reads_back_exactly(tmp_path):
    write_camera_path(tmp_path / "tour.csv", PATH)
    assert (tmp_path / "tour.csv").read_text().splitlines()[0] == "t,px,py,pz,lx,ly,lz"
    assert read_camera_path(tmp_path / "tour.csv") == PATH


@pytest.mark.parametrize("suffix", [".gltf", ".glb"])
def test_gltf_reads_back_equal_to_its_float32(tmp_path, suffix):
    """glTF keeps float32: times and eyes come back as their float32 roundings, the look-at points within a
    millionth of their distance (the quaternion's float32)."""
    write_camera_path(tmp_path / f"tour{suffix}", PATH)
    back = read_camera_path(tmp_path / f"tour{suffix}")
    assert back.name == "tour" and back.keys.shape == KEYS.shape
    assert np.array_equal(back.keys[:, :4], float32(KEYS[:, :4]))
    distances = np.linalg.norm(KEYS[:, 4:] - KEYS[:, 1:4], axis=1)
    assert np.all(np.linalg.norm(back.keys[:, 4:] - KEYS[:, 4:], axis=1) < 1e-6 * distances + 1e-3)


def test_the_cli_exports_and_imports_the_default_scenes_flythrough(tmp_path, capsys):
    flythrough = load_scene(DEFAULT_SCENE).camera_path("flythrough")
    for suffix in (".csv", ".gltf", ".glb"):
        assert main(["export", str(DEFAULT_SCENE), "--out", str(tmp_path / f"fly{suffix}")]) == 0
        assert main(["import", str(tmp_path / f"fly{suffix}"), "--out", str(tmp_path / "s.toml")]) == 0
    scene = load_scene(tmp_path / "s.toml")
    assert scene.shading == NEW_SCENE_SHADING  # a new scene's, kept through the imports into it
    paths = scene.camera_paths
    assert [p.name for p in paths] == ["fly", "fly-2", "fly-3"]  # the names in the scene kept apart
    assert np.array_equal(paths[0].keys, flythrough.keys)  # CSV: exactly
    for gltf in paths[1:]:
        assert np.allclose(gltf.keys, flythrough.keys, rtol=0.0, atol=1e-3)
    assert "fly-3: 5 keys over 30 s" in capsys.readouterr().out


def test_the_rotation_turns_gltfs_camera_to_look_as_cloudviews():
    """glTF's camera looks down -Z with +Y up: looking there is no rotation, looking along +X a quarter turn
    about +Y (clockwise from above), and any look's matrix is cloudview's camera pose."""
    assert np.allclose(rotation_quaternion((0, 0, 0), (0, 0, -5)), [0, 0, 0, 1])
    half = np.sqrt(0.5)
    assert np.allclose(rotation_quaternion((0, 0, 0), (7, 0, 0)), [0, -half, 0, half])
    for eye, look in zip(KEYS[:, 1:4], KEYS[:, 4:7]):
        matrix = quaternion_matrices(rotation_quaternion(eye, look))[0]
        assert np.allclose(matrix, camera_pose(Camera(tuple(eye), tuple(look)))[:3, :3])
        forward = (look - eye) / np.linalg.norm(look - eye)
        assert np.allclose(-matrix[:, 2], forward)


def gltf_document(tmp_path) -> dict:
    write_camera_path(tmp_path / "tour.gltf", PATH)
    return json.loads((tmp_path / "tour.gltf").read_text())


def buffer_of(document) -> bytes:
    return base64.b64decode(document["buffers"][0]["uri"].partition(",")[2])


def test_the_eye_moves_in_other_tools_as_in_cloudview(tmp_path):
    """The eye's CUBICSPLINE, evaluated as glTF's spec says (Hermite, tangents per second), is the Catmull-Rom
    path cloudview plays between the keys."""
    document = gltf_document(tmp_path)
    blob = buffer_of(document)
    times = np.frombuffer(blob, "<f4", len(KEYS)).astype(np.float64)
    view = document["bufferViews"][1]
    spline = np.frombuffer(blob, "<f4", 3 * 3 * len(KEYS), view["byteOffset"]).astype(np.float64).reshape(-1, 3, 3)
    for k in range(len(KEYS) - 1):
        dt = times[k + 1] - times[k]
        for s in (0.25, 0.5, 0.8):
            h = [2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2]
            gltf_eye = (
                h[0] * spline[k, 1] + h[1] * dt * spline[k, 2] + h[2] * spline[k + 1, 1] + h[3] * dt * spline[k + 1, 0]
            )
            assert np.allclose(gltf_eye, sample(KEYS, KEYS[k, 0] + s * (KEYS[k + 1, 0] - KEYS[k, 0]))[:3], atol=1e-2)


def test_another_tools_camera_under_an_animated_parent(tmp_path):
    """A camera node turned to look along +X under a parent moved by its own STEP and LINEAR channels, no
    cloudview extras: the keys are the union of the channels' times, each look-at point --look-distance ahead."""
    gl = pygltflib
    times_a, times_b = np.array([0.0, 1.0, 2.0], np.float32), np.array([0.5, 2.0], np.float32)
    moves = np.array([[0, 100, 0], [10, 100, 0], [20, 100, 0]], np.float32)
    lifts = np.array([[0, 0, 0], [0, 50, 0]], np.float32)
    arrays = [times_a, moves, times_b, lifts]
    blob = b"".join(a.tobytes() for a in arrays)
    views, accessors, offset = [], [], 0
    for array, kind in zip(arrays, ("SCALAR", "VEC3", "SCALAR", "VEC3")):
        views.append(gl.BufferView(buffer=0, byteOffset=offset, byteLength=array.nbytes))
        accessors.append(gl.Accessor(bufferView=len(views) - 1, componentType=5126, count=len(array), type=kind))
        offset += array.nbytes
    half = float(np.sqrt(0.5))
    document = gl.GLTF2(
        scenes=[gl.Scene(nodes=[0])],
        nodes=[
            gl.Node(name="rig", children=[2]),
            gl.Node(name="lift", children=[0]),
            gl.Node(name="cam", camera=0, rotation=[0.0, -half, 0.0, half]),
        ],
        cameras=[gl.Camera(type="perspective", perspective=gl.Perspective(yfov=0.8, znear=0.1))],
        animations=[
            gl.Animation(
                samplers=[
                    gl.AnimationSampler(input=0, output=1, interpolation="LINEAR"),
                    gl.AnimationSampler(input=2, output=3, interpolation="STEP"),
                ],
                channels=[
                    gl.AnimationChannel(sampler=0, target=gl.AnimationChannelTarget(node=0, path="translation")),
                    gl.AnimationChannel(sampler=1, target=gl.AnimationChannelTarget(node=1, path="translation")),
                ],
            )
        ],
        accessors=accessors,
        bufferViews=views,
        buffers=[gl.Buffer(byteLength=len(blob))],
    )
    document.set_binary_blob(blob)
    (tmp_path / "rig.glb").write_bytes(b"".join(document.save_to_bytes()))
    keys = read_camera_path(tmp_path / "rig.glb", "rig", look_distance_m=200.0).keys
    assert np.allclose(keys[:, 0], [0.0, 0.5, 1.0, 2.0])
    assert np.allclose(keys[:, 1:4], [[0, 100, 0], [5, 100, 0], [10, 100, 0], [20, 150, 0]], atol=1e-4)
    assert np.allclose(keys[:, 4:7] - keys[:, 1:4], [[200.0, 0.0, 0.0]] * 4, atol=1e-4)
    default = read_camera_path(tmp_path / "rig.glb").keys
    assert np.allclose(np.linalg.norm(default[:, 4:] - default[:, 1:4], axis=1), DEFAULT_LOOK_DISTANCE_M)


def mutated_gltf(change):
    """A function writing the tour's glTF, changed by `change(document)`, into a folder; its file's name."""

    def write(folder):
        document = gltf_document(folder)
        change(document)
        (folder / "bad.gltf").write_text(json.dumps(document))
        return "bad.gltf"

    return write


def csv_file(text: str):
    def write(folder):
        (folder / "bad.csv").write_text(text)
        return "bad.csv"

    return write


def raw_file(name: str, content: bytes):
    def write(folder):
        (folder / name).write_bytes(content)
        return name

    return write


def nan_translation(document):
    """The first eye's x NaN, in the buffer itself."""
    blob = bytearray(buffer_of(document))
    offset = document["bufferViews"][1]["byteOffset"] + 12  # the first key's value, after its in-tangent
    blob[offset : offset + 4] = np.float32(np.nan).tobytes()
    document["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()


def times_backwards(document):
    blob = bytearray(buffer_of(document))
    blob[4:8] = np.float32(100.0).tobytes()  # the second key after the third
    document["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()


CSV_HEADER = "t,px,py,pz,lx,ly,lz\n"
GOOD_ROWS = "0,0,0,0,1,0,0\n1,1,0,0,2,0,0\n"

BAD_FILES = {
    "csv without its header": (csv_file(GOOD_ROWS), "header: expected the columns t,px,py,pz,lx,ly,lz"),
    "csv NaN": (csv_file(CSV_HEADER + GOOD_ROWS + "2,nan,0,0,3,0,0\n"), "keys: numbers must be finite, got nan"),
    "csv absurd number": (csv_file(CSV_HEADER + "0,1e300,0,0,1,0,0\n" + GOOD_ROWS), "numbers must be within +-1e+12"),
    "csv times backwards": (csv_file(CSV_HEADER + GOOD_ROWS + "0.5,5,0,0,6,0,0\n"), "key times must increase strictly"),
    "csv short row": (csv_file(CSV_HEADER + GOOD_ROWS + "2,1,2,3,4,5\n"), "row 4: expected 7 numbers, got 6"),
    "csv words": (csv_file(CSV_HEADER + "zero,0,0,0,1,0,0\n"), "row 2: expected numbers"),
    "csv one key": (csv_file(CSV_HEADER + "0,0,0,0,1,0,0\n"), "a camera path needs at least 2 keys"),
    "csv looks at its eye": (csv_file(CSV_HEADER + GOOD_ROWS + "2,1,1,1,1,1,1\n"), "a key looks at its own position"),
    "csv too many keys": (
        csv_file(CSV_HEADER + "".join(f"{t},0,0,0,1,0,0\n" for t in range(MAX_CAMERA_KEYS + 1))),
        f"{MAX_CAMERA_KEYS + 1:,} keys, at most {MAX_CAMERA_KEYS:,}",
    ),
    "csv binary": (raw_file("bad.csv", b"\xff\xfe\x00garbage"), "not UTF-8 text"),
    "csv field of a megabyte": (csv_file(CSV_HEADER + "0," + "1" * 2**20 + ",0,0,1,0,0\n"), "not a readable CSV"),
    "gltf truncated": (
        lambda d: raw_file("bad.gltf", (d / "tour.gltf").read_bytes()[:300] if (d / "tour.gltf").exists() else b"")(d),
        "not a readable glTF file (truncated or corrupt?)",
    ),
    "glb truncated": (
        lambda d: write_camera_path(d / "t.glb", PATH) or raw_file("bad.glb", (d / "t.glb").read_bytes()[:100])(d),
        "not a readable glTF file",
    ),
    "gltf buffer outside the folder": (
        mutated_gltf(lambda doc: doc["buffers"][0].update(uri="../secret.bin")),
        "its uri '../secret.bin' leads outside the glTF file's folder",
    ),
    "gltf buffer absolute": (
        mutated_gltf(lambda doc: doc["buffers"][0].update(uri="/etc/passwd")),
        "leads outside the glTF file's folder",
    ),
    "gltf 10^12 keys claimed": (
        mutated_gltf(lambda doc: doc["accessors"][0].update(count=10**12)),
        f"a count of 1000000000000, expected 1 to {4 * MAX_CAMERA_KEYS:,}",
    ),
    "gltf accessor past its buffer": (
        mutated_gltf(lambda doc: doc["bufferViews"][0].update(byteLength=10**6)),
        "reaches past its buffer's",
    ),
    "gltf NaN": (mutated_gltf(nan_translation), "numbers must be finite, got nan"),
    "gltf times backwards": (mutated_gltf(times_backwards), "key times must increase strictly"),
    "gltf no camera": (mutated_gltf(lambda doc: doc["nodes"][0].pop("camera")), "no camera node is animated"),
    "gltf node cycle": (
        mutated_gltf(lambda doc: doc["nodes"].append({"children": [0]}) or doc["nodes"][0].update(children=[1])),
        "the node hierarchy has a cycle",
    ),
    "gltf wrong types": (mutated_gltf(lambda doc: doc.update(nodes=5)), "not a readable glTF file"),
    "gltf negative count": (
        mutated_gltf(lambda doc: doc["accessors"][0].update(count=-5)),
        f"a count of -5, expected 1 to {4 * MAX_CAMERA_KEYS:,}",
    ),
    "not a path file": (raw_file("path.txt", b"t,px\n"), "cloudview imports .vdb, .csv, .gltf, .glb files"),
    "missing": (lambda d: "nowhere.gltf", "no such file"),
}


@pytest.mark.parametrize("case", BAD_FILES)
def test_a_bad_camera_path_file_is_one_line_and_exit_2_and_the_scene_untouched(tmp_path, case, capsys):
    make, problem = BAD_FILES[case]
    folder = tmp_path / "files"
    folder.mkdir()
    name = make(folder)
    scene_file = tmp_path / "scene.toml"
    save_scene(Scene(camera_paths=(PATH,)), scene_file)
    before = scene_file.read_bytes()
    assert main(["import", str(folder / name), "--out", str(scene_file)]) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"cloudview: error: {folder / name}: ") and problem in error, error
    assert error.count("\n") == 1
    assert scene_file.read_bytes() == before


def test_exporting_a_path_the_scene_lacks_is_one_line(tmp_path, capsys):
    save_scene(Scene(camera_paths=(PATH,)), tmp_path / "s.toml")
    assert main(["export", str(tmp_path / "s.toml"), "--out", str(tmp_path / "p.csv"), "--path", "nope"]) == 2
    assert "--path: no camera path named 'nope'; the scene has: tour" in capsys.readouterr().err
    assert not (tmp_path / "p.csv").exists()
