"""1.2 million particles: frame time, a finite image and memory, in full 3D and auto mode. JSON out.

    python scripts/bench_many_particles.py [--particles 1200000] [--per-cloud 2700] [--frames 3]
                                           [--width 640 --height 480] [--json out/many_particles.json]

The default scene's world (terrain, lighting, camera) under a field of
cumulus clouds (`cloudcore.measure.bench_skies.particle_field`) of the default scene's density,
about 2,700 particles each, on a jittered grid filling the view up the valley
and beyond.  The clouds' illumination is precomputed once (timed); then
each mode renders --frames frames of the scene's camera: the first builds
every impostor, the ring of far clouds takes 16 more, the last 3 are the
steady state.  Each mode reports its frame times, what the plan drew, texture
memory, the process's resident memory and whether the linear float frame is
finite.  The numbers are in docs/robustness.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.bench_skies import particle_field  # noqa: E402
from cloudcore.measure.benchmark import machine, resident_memory_bytes, write_report  # noqa: E402  (the GL imports need the platform)
from cloudcore.model.scene import Scene  # noqa: E402
from cloudcore.model.settings import RenderSettings  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402

#: the last frames of a mode, averaged as its steady state: by then the ring (8 segments, 8 fade frames) is built
STEADY_FRAMES = 3


def finite_frame(renderer: FrameRenderer) -> dict:
    linear = renderer.context.read_linear_rgb()
    return {
        "frame_non_finite_values": int(np.count_nonzero(~np.isfinite(linear))),
        "frame_linear_max": float(np.nanmax(linear)),
    }


def bench_mode(renderer: FrameRenderer, scene: Scene, mode: str, frames: int, illumination: str) -> dict:
    stats = [
        renderer.render(scene, illumination_method=illumination, settings=RenderSettings(mode=mode), read_back=False)[1]
        for _ in range(frames)
    ]
    later, steady = stats[1:] or stats, stats[-STEADY_FRAMES:]
    last = stats[-1]
    return {
        "mode": mode,
        "frames": frames,
        "first_frame_ms": stats[0].frame_ms,
        "frame_ms_mean": float(np.mean([s.frame_ms for s in later])),
        "steady_frame_ms_mean": float(np.mean([s.frame_ms for s in steady])),
        "steady_cloud_ms_mean": float(np.mean([s.cloud_ms for s in steady])),
        "particles_drawn": last.particles_drawn,
        "clouds_drawn": last.clouds_drawn,
        "clouds_culled": last.clouds_culled,
        "clouds_ring": last.plan.clouds_by_kind["ring"],
        "impostors_drawn": last.plan.impostors_drawn,
        "texture_bytes": last.texture_bytes,
        "resident_bytes": resident_memory_bytes(),
        **finite_frame(renderer),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, default=1_200_000)
    parser.add_argument("--per-cloud", type=int, default=2_700)
    parser.add_argument(
        "--frames",
        type=int,
        default=20,
        help="frames per mode; the first builds the impostors, the ring takes 16 (default %(default)s)",
    )
    parser.add_argument("--modes", default="full,auto")
    parser.add_argument("--illumination", choices=("exact", "raster"), default="exact")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    args = parser.parse_args()

    start = time.perf_counter()
    scene = dataclasses.replace(load_scene(DEFAULT_SCENE), clouds=particle_field(args.particles, args.per_cloud))
    generated_s = time.perf_counter() - start
    result = {
        "particles": scene.particle_count,
        "clouds": len(scene.clouds),
        "width": args.width,
        "height": args.height,
        "illumination": args.illumination,
        "generation_s": generated_s,
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
        "resident_bytes_before": resident_memory_bytes(),
    }
    with FrameRenderer(args.width, args.height) as renderer:
        _, first = renderer.render(
            scene, illumination_method=args.illumination, settings=RenderSettings(mode="full"), read_back=False
        )
        result["illumination_ms"] = first.illumination_ms
        result["runs"] = [
            bench_mode(renderer, scene, mode, args.frames, args.illumination) for mode in args.modes.split(",")
        ]
    write_report(result, args.json)


if __name__ == "__main__":
    main()
