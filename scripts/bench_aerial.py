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
import os
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl.frame import FrameRenderer  # noqa: E402  (after the platform above)
from cloudcore.measure.benchmark import machine, setting_in_turns, write_report  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import FULL_3D, RenderSettings  # noqa: E402

#: the representations, each drawn with and without the air in turns
REPRESENTATIONS = {"full": FULL_3D, "auto": RenderSettings()}
TIMINGS = ("world_ms", "cloud_ms", "impostor_update_ms", "frame_ms")


def pass_costs(scene, width: int, height: int, repeat: int, warm_up: int) -> dict:
    """Per representation, with the air ("on") and without ("off"), the median of each of `TIMINGS` over `repeat`
    frames, ms; one renderer (the volume is built once, the camera still)."""
    with FrameRenderer(width, height) as renderer:
        costs = setting_in_turns(
            {"on": renderer, "off": renderer}, scene, REPRESENTATIONS, "aerial_perspective", TIMINGS, repeat, warm_up
        )
    return {"size": f"{width}x{height}", **costs}


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
