"""The truth's convergence: its noise against samples per pixel, and the time, JSON out.

    python scripts/truth_convergence.py [SCENE] [--spp 16,64,256] [--time-of-day 12] [--json out/truth_convergence.json]

At each sample count the default view is path traced with two seeds (`cloudcore.measure.truth.render_truth`);
the PSNR between the two pictures measures the noise (one picture against the converged one is about
3 dB better, the two noises being independent).  Results for this machine are in docs/shading.md.
"""

from __future__ import annotations

import argparse
import platform
from pathlib import Path

from cloudcore.maths.colour import linear_to_srgb8
from cloudcore.measure.benchmark import machine, write_report
from cloudcore.measure.imagecompare import compare
from cloudcore.measure.truth import render_truth
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--spp", default="16,64,256")
    parser.add_argument("--time-of-day", type=float, help="time of day in hours, overriding the scene's")
    parser.add_argument("--width", type=int, default=160)
    parser.add_argument("--height", type=int, default=120)
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    rows = []
    for spp in (int(n) for n in args.spp.split(",")):
        first, second = (
            render_truth(scene, args.width, args.height, time_of_day=args.time_of_day, spp=spp, seed=seed)
            for seed in (0, 1)
        )
        noise = compare(linear_to_srgb8(first.linear), linear_to_srgb8(second.linear))
        rows.append({"spp": spp, "seconds": first.seconds, "noise_psnr_db": noise.psnr_db, "variant": first.variant})
        print(f"{spp} spp: {first.seconds:.1f} s, two seeds {noise}")
    report = {
        "scene": args.scene,
        "machine": machine(),
        "python": platform.python_version(),
        "width": args.width,
        "height": args.height,
        "time_of_day": args.time_of_day,
        "rows": rows,
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
