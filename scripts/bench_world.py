"""The world pass with and without 4x multisampling: its time beside the picture it changes. JSON out.

    python scripts/bench_world.py [SCENE] [--sizes 640x480,1280x800] [--repeat 9] [--json out/bench_world.json]

Renders the scene's view in full 3D at each size, alternating the two
settings frame by frame (so both see the same machine load), and reports the
world pass's best time of --repeat for each, their ratio, and the whole
frame's difference (PSNR, share of pixels off by more than 8 levels): what
`world_antialiasing` buys (`cloudcore.gl.context`).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402  (the GL imports need the platform above)
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import FULL_3D  # noqa: E402


def measure(scene, width: int, height: int, repeat: int) -> dict:
    settings = {aa: dataclasses.replace(FULL_3D, world_antialiasing=aa) for aa in (False, True)}
    best, images = {False: np.inf, True: np.inf}, {}
    with FrameRenderer(width, height) as renderer:
        for frame in range(repeat + 1):
            for antialiased, chosen in settings.items():
                images[antialiased], stats = renderer.render(scene, settings=chosen)
                if frame:  # the first of each builds the world's buffers
                    best[antialiased] = min(best[antialiased], stats.world_ms)
    difference = compare(images[False], images[True])
    off = np.abs(images[False].astype(int) - images[True].astype(int)).max(axis=2) > 8
    return {
        "size": f"{width}x{height}",
        "world_ms": best[False],
        "world_ms_antialiased": best[True],
        "antialiasing_costs_x": best[True] / best[False],
        "psnr_db_without_against_with": difference.psnr_db,
        "pixels_off_by_more_than_8": float(off.mean()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--sizes", default="640x480,1280x800")
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(args.scene)
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    rows = [measure(scene, width, height, args.repeat) for width, height in sizes]
    write_report({"machine": machine(), "scene": str(args.scene), "sizes": rows}, args.json)


if __name__ == "__main__":
    main()
