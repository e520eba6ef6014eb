"""Long run: a camera path looped headless for minutes; texture and process memory must stay flat. JSON out.

    python scripts/bench_longrun.py [cloudcore/resources/scenes/valley.toml] [--camera-path flythrough] [--minutes 10]
                                    [--width 640 --height 480] [--mode auto] [--json out/longrun.json]

Renders the path's frames (--fps per second of path time) over and over, as
the editor's viewport would, for --minutes of wall time.  Samples the
renderer's texture memory (impostors, ring, screen layers) and the process's
resident memory before the first frame, after it, after the first loop of the
path, every --sample-seconds, and at the end, with the frames rendered and
their mean time since the last sample and a check that the linear float frame
is finite.  Memory is flat when the end matches the end of the first loop.
The numbers are in docs/robustness.md.
"""

from __future__ import annotations

import argparse
import itertools
import os
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.benchmark import machine, path_views, resident_memory_bytes, write_report  # noqa: E402  (the GL imports need the platform)
from cloudcore.model.settings import MODES, RenderSettings  # noqa: E402
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scenes.files import load_scene  # noqa: E402


def sample(renderer: FrameRenderer, started: float, frames: int, frame_ms: list[float]) -> dict:
    """Where memory stands now, and the frames since the last sample."""
    linear = renderer.context.read_linear_rgb() if renderer.last_plan is not None else np.zeros(1)
    return {
        "elapsed_s": time.perf_counter() - started,
        "frames": frames,
        "texture_bytes": renderer.texture_bytes,
        "resident_bytes": resident_memory_bytes(),
        "frame_ms_mean": float(np.mean(frame_ms)) if frame_ms else None,
        "frame_finite": bool(np.isfinite(linear).all()),
    }


def long_run(scene, views, settings: RenderSettings, size, seconds: float, sample_seconds: float) -> dict:
    with FrameRenderer(*size) as renderer:
        started = time.perf_counter()
        samples, frame_ms, frames, total_ms = [sample(renderer, started, 0, [])], [], 0, 0.0
        next_sample = started + sample_seconds
        for time_s, camera in itertools.cycle(views):
            _, stats = renderer.render(scene, camera=camera, settings=settings, time_s=time_s)
            frames += 1
            frame_ms.append(stats.frame_ms)
            total_ms += stats.frame_ms if frames > 1 else 0.0  # the first frame builds every impostor
            now = time.perf_counter()
            finished = now - started >= seconds
            if frames in (1, len(views)) or now >= next_sample or finished:
                samples.append(sample(renderer, started, frames, frame_ms))
                frame_ms = []
                while next_sample <= now:
                    next_sample += sample_seconds
            if finished:
                break
    before, first, last = samples[0], samples[1], samples[-1]
    # memory is compared from the end of the first loop, when every cache along the path has filled
    warm = next((s for s in samples if s["frames"] == len(views)), None)
    return {
        "frames": frames,
        "loops": frames / len(views),
        "seconds": last["elapsed_s"],
        "frame_ms_mean": total_ms / max(frames - 1, 1),
        "first_frame_ms": first["frame_ms_mean"],
        "texture_bytes_after_first_frame": first["texture_bytes"],
        "texture_bytes_after_first_loop": warm and warm["texture_bytes"],
        "texture_bytes_end": last["texture_bytes"],
        "texture_bytes_max": max(s["texture_bytes"] for s in samples),
        "resident_bytes_start": before["resident_bytes"],
        "resident_bytes_after_first_frame": first["resident_bytes"],
        "resident_bytes_after_first_loop": warm and warm["resident_bytes"],
        "resident_bytes_end": last["resident_bytes"],
        "resident_bytes_max": max(s["resident_bytes"] for s in samples),
        "sampled_frames_finite": all(s["frame_finite"] for s in samples),
        "samples": samples,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--camera-path", default="flythrough", help="camera path to loop (default %(default)s)")
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--sample-seconds", type=float, default=60.0)
    # 5 frames per second of path time: llvmpipe loops the 30 s flythrough (151 frames) about 8 times in 10 minutes
    parser.add_argument("--fps", type=float, default=5.0, help="frames per second of path time (default %(default)s)")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--mode", choices=MODES, default="auto")
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    path = scene.camera_path(args.camera_path)
    views = path_views(scene, args.camera_path, max(2, round(path.duration * args.fps) + 1))
    result = {
        "scene": str(args.scene),
        "path": args.camera_path,
        "mode": args.mode,
        "width": args.width,
        "height": args.height,
        "minutes": args.minutes,
        "path_frames": len(views),
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
        **long_run(
            scene,
            views,
            RenderSettings(mode=args.mode),
            (args.width, args.height),
            60.0 * args.minutes,
            args.sample_seconds,
        ),
    }
    write_report(result, args.json, {k: v for k, v in result.items() if k != "samples"})


if __name__ == "__main__":
    main()
