"""Camera paths through `cloudview import` and `cloudview export`: glTF camera animation (.gltf, .glb) and CSV.

    cloudview import PATH.gltf --out SCENE.toml [--name NAME] [--look-distance M]
    cloudview export SCENE.toml --out PATH.glb [--path NAME]

An imported path is added to the scene (made, looking from its first key, where it is missing) under its
name, or the file's stem, a number added where the scene has a path of that name.  A file that cannot be
imported is one line naming it and the problem, exit status 2, and the scene is not touched.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from cloudcore.model.errors import SceneError
from cloudcore.model.scene import NEW_SCENE_SHADING, Camera, Scene
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.interop.camera_paths import DEFAULT_LOOK_DISTANCE_M, read_camera_path, write_camera_path
from cloudcore.scenes.interop.vdb_clouds import free_name
from cloudcore.scenes.limits import scene_limit_problems


def add_import_arguments(parser) -> None:
    parser.add_argument("--name", metavar="NAME", help="a camera path's name in the scene (default: the file's stem)")
    parser.add_argument(
        "--look-distance",
        type=float,
        default=DEFAULT_LOOK_DISTANCE_M,
        metavar="M",
        help="metres ahead of a glTF camera its look-at points are put, where the file does not say "
        f"(default {DEFAULT_LOOK_DISTANCE_M:g})",
    )


def add_export_arguments(parser) -> None:
    parser.add_argument("--path", metavar="NAME", help="the camera path to export (default: the scene's first)")


def run_import(file: Path, out: Path, name: str | None, look_distance_m: float) -> int:
    scene = load_scene(out) if out.exists() else None
    path = read_camera_path(file, name, look_distance_m)
    if scene is None:
        first = path.keys[0]
        scene = Scene(camera=Camera(tuple(first[1:4].tolist()), tuple(first[4:7].tolist())), shading=NEW_SCENE_SHADING)
    path = dataclasses.replace(path, name=free_name(path.name, [p.name for p in scene.camera_paths]))
    scene = dataclasses.replace(scene, camera_paths=scene.camera_paths + (path,))
    problems = scene_limit_problems(scene)
    if problems:
        raise SceneError(str(file), *problems[0])
    save_scene(scene, out)
    print(f"{path.name}: {len(path.keys)} keys over {path.duration:.3g} s")
    print(f"wrote {out}")
    return 0


def run_export(scene_file, out: Path, name: str | None) -> int:
    scene = load_scene(scene_file)
    if not scene.camera_paths:
        raise SceneError(str(scene_file), "camera_paths", "the scene has no camera path to export")
    try:
        path = scene.camera_path(name) if name is not None else scene.camera_paths[0]
    except KeyError as error:
        raise SceneError(str(scene_file), "--path", error.args[0]) from None
    write_camera_path(out, path, scene.camera.fov_y_deg)
    print(f"{path.name}: {len(path.keys)} keys over {path.duration:.3g} s")
    print(f"wrote {out}")
    return 0
