"""Frame time of a cloud field against its rings and against its extent: 20 km of the demo's flight in auto mode (JSON).

    python scripts/bench_cloud_field.py [--stations 8] [--burst 16] [--warmup 6] [--width 320] [--height 240]
                                        [--rings 2,3,4,5,6] [--modes full,impostor] [--cells-from REV]
                                        [--detail-texels 2,4]
                                        [--json out/bench_cloud_field.json]

The demo scene (`cloudcore/resources/scenes/cumulus_field.toml`: 100 km of cumulus, 6 rings) is flown over
the first 20 km of its `flight` path (at 2 km through the clouds, then climbing above them) in auto mode
with the default settings.  A CPU cannot draw the 3,000 frames of 20 km at 200 m/s and 30 fps, and frames
kilometres apart would defeat what auto mode keeps between frames (Wang's ring lags its eye by its 16
frames of rebuild and fade; impostors are remade every frame), so the flight is sampled: `--stations`
places spread evenly over the 20 km, and at each a burst of `--burst` frames flown at 200 m/s and 30 fps
(6.7 m a frame), of which the first `--warmup` (the jump from the last station: cells entering, the ring
and impostors catching up) are reported apart.  Once per configuration: each number of `--rings` at the
demo's extent, the demo's rings at 4x its extent (400 km), and the demo in each of `--modes` (auto mode
against full 3D and impostor mode: every frame of these and of the demo compared with full 3D's, PSNR).
The configurations are interleaved frame
by frame (one renderer each, all in this process), so a load on the machine slows them alike and the
ratios hold.  Per configuration: the whole `render` call (`render_ms`: the field's update, lighting entering
cells and rebuilding the particle buffer, the passes), the renderer's own frame time (`frame_ms`: the passes
only), the cloud pass and impostor updates, the field's particles, the cells made per frame, what preparing
the particles costs where cells entered (`illumination_ms`), and the pure field update on its own
(`update_field`, timed beside the renderer).  `--cells-from REV` flies the demo a second time in auto mode and in
each of `--modes` with git revision REV's cells and demo (`cloudcore/field/cells.py`, what a cell's particles
are, and the demo scene as they were there), interleaved with this tree's, so a change to the clouds'
structure is measured before and after in one run (each frame of REV's compared with REV's full 3D).
`--detail-texels V1,V2,...` flies the demo again in impostor mode and in auto at each value of
`impostor_detail_texels`, beside the rest (the texture detail measured on the field: docs/lod.md).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import subprocess
import tempfile
import time
import types
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import cloudcore.field.state  # noqa: E402
from cloudcore.field.state import FieldState, update_field  # noqa: E402
from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.maths.paths import camera_on_path  # noqa: E402
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402
from cloudcore.resources import CUMULUS_FIELD  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

#: the cells' module and the demo scene, as paths in the repository (`--cells-from`)
CELLS, DEMO = "cloudcore/field/cells.py", "cloudcore/resources/scenes/cumulus_field.toml"
#: how much of the flight is flown, metres (the issue's 20 km)
FLOWN_M = 20000.0
#: metres a frame at 200 m/s and 30 frames a second
FRAME_STEP_M = 200.0 / 30.0
#: the modes `--detail-texels` flies the demo in at each of its values
MODES = ("impostor", "auto")


def views_along(scene, path_name: str, distances_m) -> list:
    """Cameras at `distances_m` metres along the path (by arc length)."""
    path = scene.camera_path(path_name)
    times = np.linspace(0.0, path.duration, 4001)
    eyes = np.array([camera_on_path(path, t, scene.camera.fov_y_deg).position for t in times])
    travelled = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(eyes, axis=0), axis=1))])
    if travelled[-1] < max(distances_m):
        raise SystemExit(f"the path is {travelled[-1]:.0f} m long, shorter than {max(distances_m):.0f} m")
    return [camera_on_path(path, t, scene.camera.fov_y_deg) for t in np.interp(distances_m, travelled, times)]


def _at_revision(revision: str, path: str) -> str:
    """The text of `path` at git `revision`."""
    root = Path(__file__).resolve().parent.parent
    return subprocess.run(
        ["git", "show", f"{revision}:{path}"], cwd=root, capture_output=True, text=True, check=True
    ).stdout


def cells_of_revision(revision: str) -> types.ModuleType:
    """`cloudcore/field/cells.py` as it was at git `revision`, as a module of its own."""
    module = types.ModuleType(f"cells_at_{revision}")
    exec(compile(_at_revision(revision, CELLS), f"{revision}:{CELLS}", "exec"), module.__dict__)
    return module


def demo_of_revision(revision: str):
    """The demo scene as it was at git `revision`."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "cumulus_field.toml"
        path.write_text(_at_revision(revision, DEMO))
        return load_scene(path)


@contextlib.contextmanager
def cells_from(module: types.ModuleType | None):
    """The field's step makes cells with `module`'s `cell_clouds` meanwhile (this tree's with None)."""
    own = cloudcore.field.state.cell_clouds
    cloudcore.field.state.cell_clouds = own if module is None else module.cell_clouds
    try:
        yield
    finally:
        cloudcore.field.state.cell_clouds = own


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stations", type=int, default=8)
    parser.add_argument("--burst", type=int, default=16)
    parser.add_argument("--warmup", type=int, default=6)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument(
        "--rings", default="2,3,4,5,6", help="ring counts to fly at the demo's extent (its own is always flown)"
    )
    parser.add_argument("--modes", default="full,impostor", help="modes to fly the demo in beside auto ('' none)")
    parser.add_argument("--cells-from", help="a git revision whose cells fly the demo beside this tree's")
    parser.add_argument(
        "--detail-texels",
        default="",
        help="impostor_detail_texels values to fly the demo at in impostor mode and auto beside the others ('' none)",
    )
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()

    demo = load_scene(CUMULUS_FIELD)
    field = demo.cloud_field
    ring_counts = sorted({*map(int, args.rings.split(",")), field.rings})  # the demo's own: the reference
    configurations = {f"rings={rings}": dataclasses.replace(field, rings=rings) for rings in ring_counts}
    configurations[f"rings={field.rings} extent=4x"] = dataclasses.replace(
        field, extent=tuple(4.0 * side for side in field.extent)
    )
    scenes = {name: dataclasses.replace(demo, cloud_field=f) for name, f in configurations.items()}
    demo_name = f"rings={field.rings}"
    settings = dict.fromkeys(scenes, RenderSettings())  # auto mode
    modes = [mode for mode in args.modes.split(",") if mode]
    for mode in modes:
        scenes[f"mode={mode}"], settings[f"mode={mode}"] = demo, RenderSettings(mode=mode)
    details = [
        f"mode={mode} detail_texels={value}" for value in args.detail_texels.split(",") if value for mode in MODES
    ]
    for name in details:
        mode, value = (part.split("=")[1] for part in name.split())
        scenes[name], settings[name] = demo, RenderSettings(mode=mode, impostor_detail_texels=float(value))
    # configuration -> the full 3D configuration its frames are compared with
    measured = [demo_name, *(f"mode={mode}" for mode in modes), *details]
    compared = dict.fromkeys(measured, "mode=full") if "full" in modes else {}
    revision_cells = {}
    if args.cells_from:
        module, revision_demo = cells_of_revision(args.cells_from), demo_of_revision(args.cells_from)
        for mode in ["auto", *modes]:
            name = f"{args.cells_from}:mode={mode}"
            scenes[name], settings[name], revision_cells[name] = revision_demo, RenderSettings(mode=mode), module
            if "full" in modes:
                compared[name] = f"{args.cells_from}:mode=full"
    renderers = {name: FrameRenderer(args.width, args.height) for name in scenes}
    states = dict.fromkeys(scenes, FieldState())
    rows = {name: [] for name in scenes}
    stations = np.linspace(0.0, FLOWN_M - args.burst * FRAME_STEP_M, args.stations)
    distances = (stations[:, None] + FRAME_STEP_M * np.arange(args.burst)).ravel()
    for frame, camera in enumerate(views_along(demo, "flight", distances)):
        images = {}
        for name, scene in scenes.items():
            with cells_from(revision_cells.get(name)):
                start = time.perf_counter()
                field_frame, states[name] = update_field(scene.cloud_field, camera.position, states[name])
                update_ms = 1e3 * (time.perf_counter() - start)
                start = time.perf_counter()
                images[name], stats = renderers[name].render(
                    scene, camera=camera, settings=settings[name], read_back=name in compared
                )
                render_ms = 1e3 * (time.perf_counter() - start)
            radii = np.concatenate([cloud.radii for cloud in field_frame.clouds])
            rows[name].append(
                {
                    "frame": frame,
                    "distance_m": float(distances[frame]),
                    "warmup": frame % args.burst < args.warmup,
                    "render_ms": render_ms,
                    "frame_ms": stats.frame_ms,
                    "cloud_ms": stats.cloud_ms,
                    "impostor_update_ms": stats.impostor_update_ms,
                    "world_ms": stats.world_ms,
                    "illumination_ms": stats.illumination_ms,
                    "field_update_ms": update_ms,
                    "field_particles": field_frame.particle_count,
                    "field_clouds": sum(len(cloud.particles) > 0 for cloud in field_frame.clouds),
                    "median_particle_radius_m": float(np.median(radii)) if len(radii) else 0.0,
                    "cells_held": len(states[name].cells),
                    "cells_made": len(states[name].made),
                    "particles_drawn": stats.particles_drawn,
                    "impostors_regenerated": stats.plan.impostors_regenerated,
                    "ring_panels_drawn": stats.plan.ring_panels_drawn,
                    "clouds_inside": stats.plan.clouds_by_kind.get("inside", 0),
                }
            )
        for name, reference in compared.items():
            rows[name][-1]["psnr_db"] = min(compare(images[name], images[reference]).psnr_db, 99.0)
    for renderer in renderers.values():
        renderer.close()

    def summary(frames: list) -> dict:
        flying = [f for f in frames if not f["warmup"]]
        column = {key: np.array([f[key] for f in flying], dtype=np.float64) for key in flying[0]}
        every = {key: np.array([f[key] for f in frames], dtype=np.float64) for key in ("cells_made", "illumination_ms")}
        entering = every["cells_made"] > 0
        return {
            "median_render_ms": float(np.median(column["render_ms"])),
            "mean_render_ms": float(column["render_ms"].mean()),
            "p95_render_ms": float(np.percentile(column["render_ms"], 95)),
            "median_frame_ms": float(np.median(column["frame_ms"])),
            "mean_frame_ms": float(column["frame_ms"].mean()),
            "median_cloud_ms": float(np.median(column["cloud_ms"])),
            "mean_impostor_update_ms": float(column["impostor_update_ms"].mean()),
            "median_world_ms": float(np.median(column["world_ms"])),
            "mean_cloud_and_update_ms": float((column["cloud_ms"] + column["impostor_update_ms"]).mean()),
            "mean_ring_panels_drawn": float(column["ring_panels_drawn"].mean()),
            "mean_clouds_inside": float(column["clouds_inside"].mean()),
            **(
                {"psnr_mean_db": float(column["psnr_db"].mean()), "psnr_min_db": float(column["psnr_db"].min())}
                if "psnr_db" in column
                else {}
            ),
            "mean_field_particles": float(column["field_particles"].mean()),
            "mean_field_clouds": float(column["field_clouds"].mean()),
            "median_particle_radius_m": float(np.median(column["median_particle_radius_m"])),
            "max_cells_held": int(column["cells_held"].max()),
            "flying_frames_with_cells_made": int(np.count_nonzero(column["cells_made"])),
            "mean_field_update_ms": float(column["field_update_ms"].mean()),
            "frames_with_cells_made": int(np.count_nonzero(entering)),
            "mean_cells_made_where_any": float(every["cells_made"][entering].mean()) if entering.any() else 0.0,
            "mean_illumination_ms_where_cells_made": float(every["illumination_ms"][entering].mean())
            if entering.any()
            else 0.0,
            "first_frame": {
                key: frames[0][key] for key in ("render_ms", "frame_ms", "illumination_ms", "field_update_ms")
            },
        }

    summaries = {name: summary(frames) for name, frames in rows.items()}
    reference = summaries[demo_name]
    for numbers in summaries.values():
        for key in ("median_render_ms", "mean_render_ms", "p95_render_ms", "median_frame_ms"):
            numbers[f"{key}_ratio_to_demo"] = numbers[key] / reference[key]
    report = {
        "command": "python scripts/bench_cloud_field.py "
        f"--stations {args.stations} --burst {args.burst} --warmup {args.warmup} "
        f"--width {args.width} --height {args.height} --rings {args.rings} --modes {args.modes}"
        + (f" --detail-texels {args.detail_texels}" if args.detail_texels else "")
        + (f" --cells-from {args.cells_from}" if args.cells_from else ""),
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
        "flown_m": FLOWN_M,
        "frame_step_m": FRAME_STEP_M,
        "summaries": summaries,
        "frames_by_configuration": rows,
    }
    write_report(report, args.json, summary={"command": report["command"], "summaries": summaries})


if __name__ == "__main__":
    main()
