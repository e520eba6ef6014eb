"""`cloudview import FILE --out SCENE.toml`: each float grid of an OpenVDB file (.vdb) as a cloud of particles,
or a camera path from a glTF (.gltf, .glb) or CSV file (`cloudcore.cli.camera_path_files`).

The clouds are added to SCENE.toml where it exists, else a new scene is made that looks at them; their
particles go into .npy files beside it.  One line per cloud says its particles and the density error the fit
leaves (`cloudcore.scenes.interop.density_fit`).  A file that cannot be imported is one line and exit 2, and the
scene is not touched.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from cloudcore.cli import camera_path_files
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import NEW_SCENE_SHADING, Camera, Scene, splats_bounding_sphere
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.interop.camera_paths import CAMERA_PATH_SUFFIXES
from cloudcore.scenes.interop.vdb_clouds import DEFAULT_PARTICLES, import_vdb_clouds
from cloudcore.scenes.limits import scene_limit_problems


def add_parser(commands) -> None:
    parser = commands.add_parser(
        "import", help="OpenVDB density grids as clouds of particles, or a glTF or CSV camera path, into a scene"
    )
    parser.add_argument(
        "vdb",
        type=Path,
        metavar="FILE",
        help="OpenVDB file (.vdb: each float grid becomes a cloud), or a camera path (.gltf, .glb, .csv)",
    )
    parser.add_argument(
        "--out",
        required=True,
        type=Path,
        metavar="SCENE.toml",
        help="scene to add the clouds or the camera path to (made if missing)",
    )
    parser.add_argument(
        "--particles",
        type=particle_budget,
        default=DEFAULT_PARTICLES,
        metavar="N",
        help=f"particles of all the file's clouds, at most (default {DEFAULT_PARTICLES:,})",
    )
    parser.add_argument(
        "--extinction",
        type=float,
        default=1.0,
        metavar="PER_M",
        help="extinction (1/m) per unit of the file's density (default 1: the file holds extinction, "
        "as `cloudview export` writes it)",
    )
    camera_path_files.add_import_arguments(parser)
    parser.set_defaults(run=run)


def particle_budget(text: str) -> int:
    """A number of particles; argparse names this function in its refusal."""
    value = int(text)
    if not 1 <= value <= 10_000_000:
        raise ValueError(text)
    return value


def run(args) -> int:
    if args.vdb.suffix.lower() in CAMERA_PATH_SUFFIXES:
        return camera_path_files.run_import(args.vdb, args.out, args.name, args.look_distance)
    if args.vdb.suffix.lower() != ".vdb":
        known = ", ".join((".vdb", *CAMERA_PATH_SUFFIXES))
        raise SceneError(str(args.vdb), "(file)", f"cloudview imports {known} files, told apart by their suffix")
    scene = load_scene(args.out) if args.out.exists() else None
    imported = import_vdb_clouds(
        args.vdb, args.particles, args.extinction, [cloud.name for cloud in scene.clouds] if scene else ()
    )
    clouds = tuple(item.cloud for item in imported)
    if scene is None:
        scene = Scene(camera=camera_looking_at(clouds), shading=NEW_SCENE_SHADING)
    scene = dataclasses.replace(scene, clouds=scene.clouds + clouds)
    problems = scene_limit_problems(scene)
    if problems:
        raise SceneError(str(args.vdb), *problems[0])
    save_scene(scene, args.out)
    for item in imported:
        fit = item.fit
        print(
            f"{item.cloud.name}: {len(fit.particles):,} particles from {len(item.grid.density):,} voxels "
            f"(blocks of {fit.block:.2f} voxels), optical depth {fit.optical_depth:.3g}; "
            f"density error L1 {100 * fit.relative_l1:.1f}%, L2 {100 * fit.relative_l2:.1f}%"
        )
    print(f"wrote {args.out}")
    return 0


def camera_looking_at(clouds) -> Camera:
    """A camera in front of the clouds (+z of them, a little above), all of them in its 60-degree view."""
    particles = np.concatenate([cloud.particles for cloud in clouds])
    centre, radius = splats_bounding_sphere(particles[:, :3], particles[:, 3])
    eye = centre + np.array([0.0, 0.3, 2.2]) * radius
    return Camera(tuple(float(v) for v in eye), tuple(float(v) for v in centre), 60.0)
