"""Shading throughput and accuracy: exact against raster on a scene, JSON out.

    python scripts/bench_shading.py [resources/scenes/valley.toml] [--json out/bench_shading.json]

For each active light of the scene, shades every cloud with the exact method
and with the raster method at several resolutions (best of --repeat runs),
and reports seconds, particles per second and the raster error against exact
(max and mean absolute).  Results for this machine are in docs/shading.md.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from cloudcore.illumination import illuminate_clouds
from cloudcore.lighting import active_lights, scene_lights
from cloudcore.scene import Scene
from cloudcore.scenefile import load_scene
from cloudcore.shading import DEFAULT_RASTER_RESOLUTION

DEFAULT_SCENE = Path(__file__).resolve().parents[1] / "resources" / "scenes" / "valley.toml"


def timed_shading(scene: Scene, light, method: str, repeat: int, resolution: int = DEFAULT_RASTER_RESOLUTION) -> tuple[float, np.ndarray]:
    best, result = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = illuminate_clouds(scene.clouds, scene.shading, (light,), method, resolution=resolution)
        best = min(best, time.perf_counter() - start)
    return best, np.concatenate(result)[:, 0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--resolutions", default=f"32,{DEFAULT_RASTER_RESOLUTION},96")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    lights, _ = scene_lights(scene.lighting)
    rows = []
    for index, light in enumerate(active_lights(lights)):
        exact_s, exact = timed_shading(scene, light, "exact", args.repeat)
        rows.append({"light": index, "method": "exact", "seconds": exact_s, "particles": len(exact),
                     "particles_per_second": len(exact) / exact_s, "max_abs_error_vs_exact": 0.0,
                     "mean_abs_error_vs_exact": 0.0})
        for resolution in (int(r) for r in args.resolutions.split(",")):
            seconds, raster = timed_shading(scene, light, "raster", args.repeat, resolution=resolution)
            error = np.abs(raster - exact)
            rows.append({"light": index, "method": f"raster-{resolution}", "seconds": seconds,
                         "particles": len(raster), "particles_per_second": len(raster) / seconds,
                         "max_abs_error_vs_exact": float(error.max()),
                         "mean_abs_error_vs_exact": float(error.mean())})
    report = {"scene": args.scene, "machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
              "python": platform.python_version(), "clouds": len(scene.clouds),
              "particles": scene.particle_count, "shading": rows}
    text = json.dumps(report, indent=2)
    print(text)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(text + "\n")


if __name__ == "__main__":
    main()
