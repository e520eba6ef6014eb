"""The octaves light passes against Harris's exact one: seconds per light, side by side, JSON out.

    python scripts/bench_octaves.py [SCENE] [--repeat 5] [--json out/bench_octaves.json]

For each light that contributes at the scene's hour (and the ground's bounce where the scene turns it on), the
methods take turns (`illuminate_direction` over every cloud, after one warm-up each), so what the shared machine
does falls on all; each octaves pass's ratio to exact is reported with its 95% interval (`ratio_interval`) and the
range of the turns' own ratios.  Results for this
machine are in docs/shading.md ("Octaves", "The light a lit face sends back").
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from cloudcore.light.ground_bounce import cloud_lights, ground_albedo_rgb
from cloudcore.light.illumination import illuminate_direction, light_directions
from cloudcore.light.lighting import scene_lights
from cloudcore.measure.benchmark import machine, ratio_interval, write_report
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene

METHODS = ("exact", "octaves", "octaves-lit-face")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    scene = load_scene(args.scene)
    # with `[shading] ground_bounce` the ground's bounce is one more light, from the nadir
    lights, _ = cloud_lights(
        *scene_lights(scene.lighting), scene.shading, ground_albedo_rgb(scene.terrain, scene.lighting.air)
    )
    rows = []
    for direction in light_directions(lights):
        seconds = {method: [] for method in METHODS}
        for turn in range(args.repeat + 1):
            for method in METHODS:
                start = time.perf_counter()
                illuminate_direction(scene.clouds, scene.shading, direction, method)
                if turn > 0:  # the first turn warms up
                    seconds[method].append(time.perf_counter() - start)
        row = {
            "direction": direction,
            "seconds": {method: sorted(times)[len(times) // 2] for method, times in seconds.items()},
            "runs": seconds,
        }
        for method in METHODS[1:]:
            ratio, low, high = ratio_interval(seconds[method], [seconds["exact"]])
            # with fewer turns than the bootstrap's block the interval is one point: the turns' own ratios beside it
            per_turn = [this / exact for this, exact in zip(seconds[method], seconds["exact"])]
            row[f"{method}_over_exact"] = {
                "ratio": ratio,
                "low": low,
                "high": high,
                "per_turn": {"min": min(per_turn), "max": max(per_turn)},
            }
        rows.append(row)
    report = {"scene": args.scene, "machine": machine(), "particles": scene.particle_count, "lights": rows}
    write_report(report, args.json)


if __name__ == "__main__":
    main()
