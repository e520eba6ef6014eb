"""Full-3D frame time and overdraw of a scene at several sizes: the record impostors must beat. JSON out.

    python scripts/bench_full3d.py [cloudcore/resources/scenes/valley.toml] [--sizes 640x480,1600x1200]
                                   [--camera-path flythrough --frames 8] [--json out/bench_full3d.json]

For each size renders the scene's camera view, then --frames views spread along
--camera-path (if given), after one warm-up frame that pays the shading precompute;
reports frame, world-pass and cloud-pass times (mean and median, timed to
glFinish, read-back excluded) and measured and analytic overdraw.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.benchmark import machine, path_views, write_report  # noqa: E402  (the GL imports need the platform above)
from cloudcore.model.settings import FULL_3D  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

_TIMES = ("frame_ms", "world_ms", "cloud_ms")


def bench_size(scene, width: int, height: int, views) -> dict:
    samples = []
    with FrameRenderer(width, height) as renderer:
        renderer.render(scene, camera=views[0], settings=FULL_3D)  # shading precompute, shader compiles
        for camera in views:
            _, stats = renderer.render(scene, camera=camera, settings=FULL_3D)
            samples.append(stats.with_overdraw(renderer.measure_overdraw()[1]).as_dict())
    summary = {
        "width": width,
        "height": height,
        "frames": len(samples),
        "particles_drawn_mean": float(np.mean([s["particles_drawn"] for s in samples])),
    }
    for key in _TIMES:
        summary[f"{key}_mean"] = float(np.mean([s[key] for s in samples]))
        summary[f"{key}_median"] = float(np.median([s[key] for s in samples]))
    summary["overdraw_mean"] = float(np.mean([s["overdraw_mean"] for s in samples]))
    summary["overdraw_max"] = float(np.max([s["overdraw_max"] for s in samples]))
    summary["overdraw_analytic_mean"] = float(np.mean([s["overdraw_analytic"] for s in samples]))
    summary["per_frame"] = samples
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--sizes", default="640x480,1600x1200")
    parser.add_argument("--camera-path", help="also time views along this camera path")
    parser.add_argument("--frames", type=int, default=8, help="views along --camera-path")
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    views = [scene.camera] + (
        [camera for _, camera in path_views(scene, args.camera_path, args.frames)] if args.camera_path else []
    )
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    result = {
        "scene": str(args.scene),
        "path": args.camera_path,
        "machine": machine(),
        "runs": [bench_size(scene, w, h, views) for w, h in sizes],
    }
    write_report(result, args.json, [{k: v for k, v in run.items() if k != "per_frame"} for run in result["runs"]])


if __name__ == "__main__":
    main()
