"""Aerial perspective's cost in a frame: the world pass and the cloud pass of a scene's view, with and without it.

    python scripts/bench_aerial.py [SCENE] [--sizes 640x480,1280x800] [--repeat 15] [--json out/bench_aerial.json]

Each size in one renderer: full 3D, then auto (the default settings, impostors after the first frames), each with
the air and without (`RenderSettings.aerial_perspective`) in turns frame by frame so that both see the
same machine load (this machine is shared: runs minutes apart differed by half); the medians of --repeat frames
after --warm-up frames, of the frame's own timings (`FrameStats.world_ms`, `cloud_ms`, `impostor_update_ms`).
The camera stays still, so the aerial-perspective volume is built once (its build is in bench_sky.py's tables).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402  (after the platform above)
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import FULL_3D, RenderSettings  # noqa: E402

#: the representations, each drawn with and without the air in turns
REPRESENTATIONS = {"full": FULL_3D, "auto": RenderSettings()}
TIMINGS = ("world_ms", "cloud_ms", "impostor_update_ms", "frame_ms")


def pass_costs(scene, width: int, height: int, repeat: int, warm_up: int) -> dict:
    """Per representation, with the air and without, the median of each of `TIMINGS` over `repeat` frames, ms."""
    row = {"size": f"{width}x{height}"}
    with FrameRenderer(width, height) as renderer:
        for name, settings in REPRESENTATIONS.items():
            # one representation at a time: auto's first frames after full 3D's remake impostors
            turns = {air: dataclasses.replace(settings, aerial_perspective=air == "air") for air in ("air", "no_air")}
            times = {air: {timing: [] for timing in TIMINGS} for air in turns}
            for frame in range(warm_up + repeat):
                for air, turn in turns.items():
                    _, stats = renderer.render(scene, settings=turn, read_back=False)
                    for timing in TIMINGS if frame >= warm_up else ():
                        times[air][timing].append(getattr(stats, timing))
            for air, named in times.items():
                row.update({f"{name}_{air}_{timing}": float(np.median(values)) for timing, values in named.items()})
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path, default=DEFAULT_SCENE)
    parser.add_argument("--sizes", default="640x480,1280x800")
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--warm-up", type=int, default=5)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    scene = load_scene(args.scene)
    sizes = [tuple(int(v) for v in size.split("x")) for size in args.sizes.split(",")]
    report = {
        "machine": machine(),
        "scene": str(args.scene),
        "sky": scene.lighting.air.sky,
        "sizes": [pass_costs(scene, width, height, args.repeat, args.warm_up) for width, height in sizes],
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
