"""Objects in clouds: split layers against the naive picture, and what the aircraft costs a flythrough.

    python scripts/bench_objects.py [--frames 301] [--json out/bench_objects.json]
                                    [--figure docs/images/split_layers.png]

1. cloudcore/resources/scenes/aircraft_in_cloud.toml at 640x480 at three instants of the
   aircraft's crossing: full 3D split (the reference), full 3D naive (splats
   depth-tested against the mesh), impostor split, impostor naive (the mesh
   depth-tested against one quad); PSNR over the frame and over the aircraft's
   screen box; the figure shows the boxes side by side.
2. The default flythrough in auto mode with the aircraft and without it,
   one after the other in one process, each in a renderer of its own (each
   keeps its own impostor cache).
3. The crossing of scene 1 from 6 to 14 s at 30 fps with the eye still, in
   impostor mode: the layers rebuilt (once the aircraft passes in depth a
   particle it covers, `cloudcore.lod.splitting.layers_hold`), the clouds'
   time and the PSNR around the aircraft against full 3D split.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.benchmark import headless_pyplot, path_views, save_figure  # noqa: E402  (GL needs the platform above)
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.model.settings import FULL_3D, RenderSettings  # noqa: E402
from cloudcore.resources import resource_path  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402
from cloudcore.world.camera import screen_box  # noqa: E402
from cloudcore.world.objects import object_poses  # noqa: E402

SCENES = resource_path("scenes")
VARIANTS = {
    "full 3D, split": FULL_3D,
    "full 3D, naive": RenderSettings(mode="full", split_objects=False),
    "impostor, split": RenderSettings(mode="impostor"),
    "impostor, naive": RenderSettings(mode="impostor", split_objects=False),
}
INSTANTS_S = (8.0, 10.0, 12.0)


def split_against_naive(size) -> tuple[list[dict], list]:
    scene = load_scene(SCENES / "aircraft_in_cloud.toml")
    rows, crops = [], []
    with FrameRenderer(*size) as renderer:
        for time_s in INSTANTS_S:
            (pose,) = object_poses(scene.objects, time_s)
            rows_, columns = screen_box(pose.centre, 1.6 * pose.radius, scene.camera, size)
            images = {
                name: renderer.render(scene, settings=settings, time_s=time_s)[0] for name, settings in VARIANTS.items()
            }
            reference = images["full 3D, split"]
            for name, image in images.items():
                whole, around = compare(image, reference), compare(image[rows_, columns], reference[rows_, columns])
                rows.append(
                    {
                        "time_s": time_s,
                        "variant": name,
                        "psnr_db": min(whole.psnr_db, 100.0),
                        "psnr_around_aircraft_db": min(around.psnr_db, 100.0),
                        "max_abs_around_aircraft": around.max_abs,
                    }
                )
            crops.append([(name, images[name][rows_, columns]) for name in VARIANTS])
    return rows, crops


def flythrough_cost(frames: int, size) -> dict:
    scene = load_scene(SCENES / "valley.toml")
    views = path_views(scene, "flythrough", frames)
    variants = {"with aircraft": scene, "without objects": dataclasses.replace(scene, objects=())}
    stats = {}
    for label, variant in variants.items():
        # one renderer each, one after the other: pyrender's EGL contexts cannot be closed while another lives
        with FrameRenderer(*size) as renderer:
            renderer.render(variant, camera=views[0][1])  # shading precompute, shader compiles
            stats[label] = [
                renderer.render(variant, camera=camera, time_s=time_s, read_back=False)[1] for time_s, camera in views
            ]
    result = {
        label: {
            "frame_ms_mean": float(np.mean([s.frame_ms for s in rows])),
            "frame_ms_p95": float(np.percentile([s.frame_ms for s in rows], 95)),
            "frames_with_object_in_cloud": int(sum(s.plan.objects_in_clouds > 0 for s in rows)),
            "layers_rebuilt": int(sum(s.plan.layers_rebuilt for s in rows)),
        }
        for label, rows in stats.items()
    }
    result["ratio"] = result["with aircraft"]["frame_ms_mean"] / result["without objects"]["frame_ms_mean"]
    return result


CROSSING_S = (6.0, 14.0)


def crossing(size) -> dict:
    scene = load_scene(SCENES / "aircraft_in_cloud.toml")
    times = np.arange(CROSSING_S[0], CROSSING_S[1], 1.0 / 30.0)
    references = {}
    with FrameRenderer(*size) as renderer:
        for time_s in times:
            references[time_s] = renderer.render(scene, settings=FULL_3D, time_s=time_s)[0]
    rebuilt, clouds_ms, around_db = 0, [], []
    with FrameRenderer(*size) as renderer:
        for time_s in times:
            image, stats = renderer.render(scene, settings=RenderSettings(mode="impostor"), time_s=time_s)
            rebuilt += stats.plan.layers_rebuilt
            clouds_ms.append(stats.impostor_update_ms + stats.cloud_ms)
            (pose,) = object_poses(scene.objects, time_s)
            rows_, columns = screen_box(pose.centre, 1.6 * pose.radius, scene.camera, size)
            reference = references[time_s]
            around_db.append(min(compare(image[rows_, columns], reference[rows_, columns]).psnr_db, 100.0))
    return {
        "frames": len(times),
        "layers_rebuilt": int(rebuilt),
        "clouds_ms_mean": float(np.mean(clouds_ms[1:])),
        "psnr_around_aircraft_mean_db": float(np.mean(around_db)),
        "psnr_around_aircraft_min_db": float(np.min(around_db)),
    }


def write_figure(crops, rows, path: Path) -> None:
    plt = headless_pyplot()
    figure, axes = plt.subplots(len(crops), len(VARIANTS), figsize=(2.3 * len(VARIANTS), 2.1 * len(crops)), dpi=110)
    for r, (row_crops, time_s) in enumerate(zip(crops, INSTANTS_S)):
        for c, (name, crop) in enumerate(row_crops):
            psnr = next(x["psnr_around_aircraft_db"] for x in rows if x["time_s"] == time_s and x["variant"] == name)
            axes[r, c].imshow(crop, interpolation="nearest")
            axes[r, c].set_xticks([])
            axes[r, c].set_yticks([])
            axes[r, c].set_title(f"{name}\nt={time_s:g} s" + ("" if c == 0 else f", {psnr:.1f} dB"), fontsize=7)
    save_figure(figure, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=301, help="flythrough frames (default 301: 10 fps)")
    parser.add_argument("--json", type=Path, default=Path("out/bench_objects.json"))
    parser.add_argument("--figure", type=Path, help="write the side-by-side crops here (PNG)")
    args = parser.parse_args()
    size = (640, 480)
    rows, crops = split_against_naive(size)
    for row in rows:
        print(
            f"t={row['time_s']:g} {row['variant']:16s} frame {row['psnr_db']:6.2f} dB, around the aircraft "
            f"{row['psnr_around_aircraft_db']:6.2f} dB (max |diff| {row['max_abs_around_aircraft']})"
        )
    cost = flythrough_cost(args.frames, size)
    print(
        f"flythrough, auto: {cost['with aircraft']['frame_ms_mean']:.1f} ms with the aircraft "
        f"({cost['with aircraft']['frames_with_object_in_cloud']} frames with it in a cloud), "
        f"{cost['without objects']['frame_ms_mean']:.1f} ms without: x{cost['ratio']:.2f}"
    )
    crossed = crossing(size)
    print(
        f"crossing, impostor mode: {crossed['layers_rebuilt']} layers rebuilt in {crossed['frames']} frames, clouds "
        f"{crossed['clouds_ms_mean']:.1f} ms, around the aircraft {crossed['psnr_around_aircraft_mean_db']:.2f} dB "
        f"mean, {crossed['psnr_around_aircraft_min_db']:.2f} worst"
    )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    result = {
        "width": size[0],
        "height": size[1],
        "split_against_naive": rows,
        "flythrough": cost,
        "crossing": crossed,
    }
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    if args.figure:
        write_figure(crops, rows, args.figure)


if __name__ == "__main__":
    main()
