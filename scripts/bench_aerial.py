"""Aerial perspective's cost in a frame: the world pass and the cloud pass of a scene's view under its sky.

    python scripts/bench_aerial.py [SCENE] [--sizes 640x480,1280x800] [--repeat 15] [--json out/bench_aerial.json]

Each size in one renderer: full 3D and auto (the default settings, impostors after the first frames) in turns
frame by frame, so both see the same machine load; the medians of --repeat frames after --warm-up frames, of
the frame's own timings (`FrameStats.world_ms`, `cloud_ms`, `impostor_update_ms`).  The camera stays still, so
the aerial-perspective volume is built once (its build is in bench_sky.py's tables).  It uses nothing but
`FrameRenderer.render`: run it with PYTHONPATH set to a checkout without aerial perspective for the before.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402  (after the platform above)
from cloudcore.measure.benchmark import machine, write_report  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import FULL_3D, RenderSettings  # noqa: E402

MODES = {"full": FULL_3D, "auto": RenderSettings()}
TIMINGS = ("world_ms", "cloud_ms", "impostor_update_ms", "frame_ms")


def pass_costs(scene, width: int, height: int, repeat: int, warm_up: int) -> dict:
    """Per mode, the median of each of `TIMINGS` over `repeat` frames, in ms."""
    times = {mode: {name: [] for name in TIMINGS} for mode in MODES}
    with FrameRenderer(width, height) as renderer:
        for frame in range(warm_up + repeat):
            for mode, settings in MODES.items():
                _, stats = renderer.render(scene, settings=settings, read_back=False)
                if frame >= warm_up:
                    for name in TIMINGS:
                        times[mode][name].append(getattr(stats, name))
    return {
        "size": f"{width}x{height}",
        **{
            f"{mode}_{name}": float(np.median(values))
            for mode, named in times.items()
            for name, values in named.items()
        },
    }


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
