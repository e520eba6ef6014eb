"""`cloudview export SCENE --out FILE.vdb [--merged]`: a scene's clouds as OpenVDB extinction grids; with
--out FILE.gltf, .glb or .csv one of its camera paths (`cloudcore.cli.camera_path_files`).

One float grid per cloud, named as the cloud, or with --merged one grid named `density` (what Blender's and
Houdini's volume shaders read): extinction in 1/m at voxel centres in metres, the voxel size and origin in the
grid's transform.  The file is written atomically.
"""

from __future__ import annotations

from pathlib import Path

from cloudcore.cli import camera_path_files
from cloudcore.measure.truth import DEFAULT_VOXELS_PER_RADIUS
from cloudcore.scenes.files import load_scene
from cloudcore.scenes.interop.camera_paths import CAMERA_PATH_SUFFIXES
from cloudcore.scenes.interop.vdb_clouds import export_vdb


def add_parser(commands) -> None:
    parser = commands.add_parser(
        "export", help="a scene's clouds as OpenVDB extinction grids, or a camera path as glTF or CSV"
    )
    parser.add_argument("scene", help="scene file (.toml)")
    parser.add_argument(
        "--out",
        required=True,
        type=Path,
        metavar="FILE",
        help="OpenVDB file to write (.vdb), or a camera path's (.gltf, .glb, .csv)",
    )
    parser.add_argument("--merged", action="store_true", help="one grid of all the clouds, named density")
    parser.add_argument(
        "--voxels-per-radius",
        type=float,
        default=DEFAULT_VOXELS_PER_RADIUS,
        metavar="Q",
        help=f"voxels across the median particle radius (default {DEFAULT_VOXELS_PER_RADIUS:g})",
    )
    camera_path_files.add_export_arguments(parser)
    parser.set_defaults(run=run)


def run(args) -> int:
    if args.out.suffix.lower() in CAMERA_PATH_SUFFIXES:
        return camera_path_files.run_export(args.scene, args.out, args.path)
    grids = export_vdb(load_scene(args.scene), args.out, args.merged, args.voxels_per_radius)
    for grid in grids:
        print(f"{grid.name}: {len(grid.density):,} voxels of {grid.linear[0, 0]:.3g} m")
    print(f"wrote {args.out}")
    return 0
