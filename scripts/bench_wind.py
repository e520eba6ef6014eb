"""What the wind costs auto mode: the default view, camera still, the scene clock running, with and without `[wind]`.

    python scripts/bench_wind.py [--frames 60] [--size 640x480] [--cases still,breeze,timelapse,churn,field]
                                 [--json out/bench_wind.json]

Each case is one run of `cloudcore.measure.benchmark.bench_path` (full 3D as the reference, auto beside it, taking
turns frame by frame) over `--frames` frames after `SETTLE_FRAMES` unmeasured ones, the scene clock advancing a
step each frame:

- still: the default scene as shipped (no wind), 1/30 s a frame;
- breeze: a 10 m/s westerly, 1/30 s a frame (real time: 0.33 m a frame);
- timelapse: the same wind, 2 s a frame (60 times real time: 20 m a frame);
- churn: bands from 6 m/s at the ground to 18 m/s at 3 km veering 250 -> 290 degrees, gusts of 0.4 over 45 s,
  turbulence of 30 m, 2 s a frame (the clouds relit every 10 s of the clock: every 5th frame);
- field_still, field: the cumulus field demo at its flight's first view, still camera, without wind and with the
  breeze at 2 s a frame;
- relight (not among the default cases): what leaving the light of turbulent shapes unrelit costs the picture: the
  default view at 55 s in full 3D, 320x240, its light made at rest against made at 50 s, for turbulence of 30 and
  100 m with one band and with the churn's two, and what a relight of the default scene takes.

Prints one line a case: auto's mean and 95th-percentile frame, its regenerations a frame, the largest error it
accepted (in tolerances), its PSNR against full 3D of the same frame, and the light's ms a frame (relighting and the
ground's shadow map made again).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.measure.benchmark import bench_path, machine, write_report  # noqa: E402
from cloudcore.measure.imagecompare import compare  # noqa: E402
from cloudcore.paths import camera_on_path  # noqa: E402
from cloudcore.resources import CUMULUS_FIELD, DEFAULT_SCENE  # noqa: E402
from cloudcore.scene import Wind  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import FULL_3D, RenderSettings  # noqa: E402

SETTLE_FRAMES = 20
BREEZE = Wind(bands=((0.0, 10.0, 270.0),))
CHURN = Wind(
    bands=((0.0, 6.0, 250.0), (3000.0, 18.0, 290.0)), gust_amplitude=0.4, gust_period_s=45.0, turbulence_m=30.0
)
#: case -> (scene file, wind, scene seconds a frame)
CASES = {
    "still": (DEFAULT_SCENE, None, 1.0 / 30.0),
    "breeze": (DEFAULT_SCENE, BREEZE, 1.0 / 30.0),
    "timelapse": (DEFAULT_SCENE, BREEZE, 2.0),
    "churn": (DEFAULT_SCENE, CHURN, 2.0),
    "field_still": (CUMULUS_FIELD, None, 2.0),
    "field": (CUMULUS_FIELD, BREEZE, 2.0),
}


def run_case(name: str, frames: int, size: tuple[int, int]) -> dict:
    path, wind, step = CASES[name]
    scene = dataclasses.replace(load_scene(path), wind=wind)
    camera = scene.camera
    if name.startswith("field"):  # the flight's first view: at 2 km among the clouds
        flight = scene.camera_path("flight")
        camera = camera_on_path(flight, 0.0, scene.camera.fov_y_deg)
    views = [(step * frame, camera) for frame in range(SETTLE_FRAMES + frames)]
    renderers = [FrameRenderer(*size) for _ in range(2)]
    try:
        report = bench_path(renderers, scene, "", frames, [RenderSettings()], size, views=views)
    finally:
        for renderer in renderers:
            renderer.close()
    auto = report["runs"][0]
    counted = auto["per_frame"][SETTLE_FRAMES:]
    summary = {
        "case": name,
        "seconds_a_frame": step,
        "frame_ms_mean": float(np.mean([r["frame_ms"] for r in counted])),
        "frame_ms_p95": float(np.percentile([r["frame_ms"] for r in counted], 95)),
        "regenerations_per_frame": float(np.mean([r.get("impostors_regenerated", 0) for r in counted])),
        "postponed_per_frame": float(np.mean([r.get("regenerations_postponed", 0) for r in counted])),
        "ring_segments_per_frame": float(np.mean([r.get("ring_segments_built", 0) for r in counted])),
        "accepted_error_max": float(np.max([r.get("accepted_error_tolerances", 0.0) for r in counted])),
        "psnr_mean": float(np.mean([r["psnr_db"] for r in counted])),
        "light_ms_mean": float(np.mean([r.get("illumination_ms", 0.0) for r in counted])),
        "full_3d_frame_ms_mean": float(
            np.mean([r["frame_ms"] for r in report["reference"]["per_frame"][SETTLE_FRAMES:]])
        ),
    }
    return {"summary": summary, "report": report}


def relight_error() -> list[dict]:
    """The `relight` case: PSNR of the picture lit from the shapes at rest against relit 5 s before, and the ms a
    relight takes (the frame that makes the light again)."""
    scene = load_scene(DEFAULT_SCENE)
    rows = []
    for amplitude in (30.0, 100.0):
        for bands in (BREEZE.bands, CHURN.bands):
            images, relight_ms = {}, 0.0
            for period in (10.0, 600.0):  # relit at 50 s, or the light of the clouds at rest
                wind = Wind(bands=bands, turbulence_m=amplitude, relight_period_s=period)
                with FrameRenderer(320, 240) as renderer:
                    renderer.render(dataclasses.replace(scene, wind=wind), settings=FULL_3D)
                    images[period], stats = renderer.render(
                        dataclasses.replace(scene, wind=wind), settings=FULL_3D, time_s=55.0
                    )
                    relight_ms = stats.illumination_ms if period == 10.0 else relight_ms
            difference = compare(images[600.0], images[10.0])
            rows.append(
                {
                    "turbulence_m": amplitude,
                    "bands": len(bands),
                    "psnr_db": difference.psnr_db,
                    "mean_abs": difference.mean_abs,
                    "relight_ms": relight_ms,
                }
            )
            print(
                f"relight    turbulence {amplitude:.0f} m, {len(bands)} band(s): unrelit against relit "
                f"{difference.psnr_db:.1f} dB (mean {difference.mean_abs:.2f} levels); a relight {relight_ms:.0f} ms",
                flush=True,
            )
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--cases", default=",".join(CASES), help=f"of {', '.join(CASES)}, relight")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    results = []
    for name in args.cases.split(","):
        if name == "relight":
            results.append({"summary": {"case": "relight", "rows": relight_error()}})
            continue
        result = run_case(name, args.frames, size)
        s = result["summary"]
        print(
            f"{name:10s} auto {s['frame_ms_mean']:7.1f} ms (p95 {s['frame_ms_p95']:7.1f})  "
            f"regenerations/frame {s['regenerations_per_frame']:5.2f}  postponed {s['postponed_per_frame']:4.2f}  "
            f"ring segments/frame {s['ring_segments_per_frame']:4.2f}  accepted error {s['accepted_error_max']:4.2f}  "
            f"PSNR {s['psnr_mean']:5.1f} dB  light {s['light_ms_mean']:6.1f} ms  "
            f"full 3D {s['full_3d_frame_ms_mean']:7.1f} ms",
            flush=True,
        )
        results.append(result)
    write_report({"machine": machine(), "cases": results}, args.json, [r["summary"] for r in results])
    return 0


if __name__ == "__main__":
    sys.exit(main())
