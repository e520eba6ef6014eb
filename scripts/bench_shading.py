"""Shading throughput and accuracy: exact against raster on a scene, JSON out.

    python scripts/bench_shading.py [cloudcore/resources/scenes/valley.toml] [--json out/bench_shading.json]

For each active light of the scene, shades every cloud with the exact method
and with the raster method at several resolutions (best of --repeat runs),
and reports seconds, particles per second and the raster error against exact
(max and mean absolute).  Results for this machine are in docs/shading.md.
"""

from __future__ import annotations

import argparse
import platform
from pathlib import Path

from cloudcore.light.shading import DEFAULT_RASTER_RESOLUTION
from cloudcore.measure.benchmark import machine, shading_comparison, write_report
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--resolutions", default=f"32,{DEFAULT_RASTER_RESOLUTION},96")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    rows = shading_comparison(scene, tuple(int(r) for r in args.resolutions.split(",")), args.repeat)
    for row in rows:
        row["particles_per_second"] = row["particles"] / row["seconds"]
    report = {
        "scene": args.scene,
        "machine": machine(),
        "python": platform.python_version(),
        "clouds": len(scene.clouds),
        "particles": scene.particle_count,
        "shading": rows,
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
