"""`cloudview shade SCENE`: precompute Harris illumination and report it per cloud."""

from __future__ import annotations

import time

from tqdm import tqdm

from cloudcore.cli.render import add_scene_argument
from cloudcore.light.illumination import illuminate_clouds
from cloudcore.light.lighting import active_lights, scene_lights
from cloudcore.light.shading import METHODS
from cloudcore.scenes.files import load_scene


def add_parser(commands) -> None:
    parser = commands.add_parser("shade", help="precompute cloud illumination and print statistics")
    add_scene_argument(parser)
    parser.add_argument("--method", choices=METHODS, default="exact")
    parser.set_defaults(run=run)


def run(args) -> int:
    scene = load_scene(args.scene)
    lights, _ = scene_lights(scene.lighting)
    lights = active_lights(lights)
    print(
        f"{args.scene}: {len(scene.clouds)} clouds, {scene.particle_count} particles, "
        f"{len(lights)} active light(s), method {args.method}"
    )
    print(f"{'cloud':<16}{'particles':>10}{'ms':>10}   incident light min / mean / max per light")
    rows, total = [], 0.0
    # the bar appears only on a terminal, and only once shading has taken a second
    for cloud in tqdm(scene.clouds, desc="shading", unit="cloud", delay=1.0, leave=False, disable=None):
        start = time.perf_counter()
        (incident,) = illuminate_clouds([cloud], scene.shading, lights, args.method)
        elapsed = time.perf_counter() - start
        total += elapsed
        rows.append((cloud, elapsed, incident))
    for cloud, elapsed, incident in rows:
        summary = "  ".join(f"{c.min():.3f} / {c.mean():.3f} / {c.max():.3f}" if c.size else "-" for c in incident.T)
        print(f"{cloud.name:<16}{len(cloud.particles):>10}{1e3 * elapsed:>10.1f}   {summary}")
    rate = scene.particle_count * max(len(lights), 1) / total if total > 0 else float("inf")
    print(f"total {total:.2f} s ({rate:,.0f} particle-lights per second)")
    return 0
