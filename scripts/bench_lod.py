"""The level of detail's error against run time: full 3D, impostor mode and auto side by side, five cases (JSON).

    python scripts/bench_lod.py [--cases still,orbit,flythrough,field,untuned] [--quick]
                                [--json out/bench_lod.json] [--plot docs/images/bench_lod.png]

Each case is one run of `cloudcore.measure.benchmark.bench_path` (one process, a renderer for the reference
and one for each mode, taking turns frame by frame), default settings but for the mode:

- still: the default view, camera still, 880x680 (the editor's viewport), 120 frames after 20 unmeasured
  ones (the ring built and faded in); what remains is the static error floor;
- orbit: the default view orbiting its look-at point 0.2 degrees a frame, 90 frames, 640x480, after
  the same 20 frames still;
- flythrough: the default scene's flythrough at 30 fps (901 frames), 640x480;
- field: 1.2 million particles (`bench_many_particles.cloud_field`) orbiting 0.05 degrees a frame,
  120 frames, 640x480, after 20 frames still (Harris: 10-12 fps for his largest scenes);
- untuned: two scenes the LOD was not tuned on, made here from a seed: a field of cumulus of another
  density and a stratocumulus deck (the Wang presets), each flown through at 120 m/s at 30 fps;
- wang_sparse, wang_scattered, wang_overcast (`wang` for all): Wang's three weathers by cloud-block overdraw
  (`wang_scenarios`), 1024x768, 90 frames of flight from the first;
- cumulus_line, popcorn_climb (`own` for both): two skies of our own (`wang_scenarios.own_scene`), 640x480,
  90 frames from the first;
- harris_circle_N, harris_through_N (`harris` for all): Harris's figure 8 (`harris_figure8`), N of 100 to
  12,800 clouds of 200 particles, the eye on his circle or straight through, 90 frames at 640x480 after
  20 still ones.

Auto's row gives its mean frame over the faster mode's, with a 95% interval (`ratio_interval`), counted from the
flight's frame `FIRST_COUNTED_FRAME` as the issue of its target asks (#51: its first frames fit the cost model): one
frame's time on llvmpipe varies by a fifth or more, and 30 frames left the ratio of two identical plans 5% either
way.
`--quick` shortens every case (a smoke run, not numbers to quote).  Prints one line per mode and
case; the JSON holds every frame.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parent))

import harris_figure8  # noqa: E402  (sibling scripts: Harris's figure 8, Wang's scenarios, the same 1.2M field)
import wang_scenarios  # noqa: E402
from bench_many_particles import cloud_field  # noqa: E402

from cloudcore.artist.cloudgen import preset_cloud  # noqa: E402
from cloudcore.gl import FrameRenderer  # noqa: E402
from cloudcore.light.illumination import IlluminationCache  # noqa: E402
from cloudcore.measure.benchmark import (  # noqa: E402
    bench_path,
    headless_pyplot,
    machine,
    orbit_views,
    path_views,
    ratio_interval,
    save_figure,
    still_views,
    write_report,
)
from cloudcore.resources import DEFAULT_SCENE  # noqa: E402
from cloudcore.scene import CameraPath, Scene  # noqa: E402
from cloudcore.scenefile import load_scene  # noqa: E402
from cloudcore.settings import RenderSettings  # noqa: E402

MODES = (RenderSettings(mode="impostor"), RenderSettings())
#: unmeasured frames before a still or slowly moving camera is timed: the impostors made, the ring's
#: 8 segments built and faded in over 8 frames
SETTLE_FRAMES = 20
#: auto's ratio to the faster mode counts a flight's frames from this one (the unmeasured warm-up frames count)
FIRST_COUNTED_FRAME = 10
#: frames of each of Harris's cases (`harris_figure8`): 3 s of flight
HARRIS_FRAMES = 90


def flight(name: str, start, end, look_ahead_m: float = 2000.0, speed_m_s: float = 120.0) -> CameraPath:
    """A straight, level-looking flight from `start` to `end` at `speed_m_s`, looking `look_ahead_m` ahead."""
    start, end = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    direction = (end - start) / np.linalg.norm(end - start)
    duration = float(np.linalg.norm(end - start)) / speed_m_s
    keys = [
        [t * duration, *(start + t * (end - start)), *(start + t * (end - start) + look_ahead_m * direction)]
        for t in np.linspace(0.0, 1.0, 5)
    ]
    return CameraPath(name, np.array(keys))


def untuned_scenes(valley: Scene) -> dict:
    """Two scenes the LOD was never tuned on: (scene, path name) by name."""
    cumulus = dataclasses.replace(
        valley,
        clouds=cloud_field(60_000, 1_500, seed=41),
        objects=(),
        camera_paths=(flight("through", (-900.0, 950.0, 2200.0), (700.0, 980.0, -1400.0)),),
    )
    rng = np.random.default_rng(7)
    deck = tuple(
        preset_cloud(
            "stratocumulus",
            f"deck_{i:02d}",
            (x + rng.uniform(-150, 150), rng.uniform(1150.0, 1250.0), z + rng.uniform(-150, 150)),
            seed=i,
        )
        for i, (x, z) in enumerate(
            (x, z) for x in np.arange(-2400.0, 2401.0, 1200.0) for z in np.arange(-2400.0, 2401.0, 1200.0)
        )
    )
    stratus = dataclasses.replace(
        valley,
        clouds=deck,
        objects=(),
        camera_paths=(flight("under_and_into", (2600.0, 900.0, 2600.0), (-1800.0, 1200.0, -1800.0)),),
    )
    return {"cumulus_field": (cumulus, "through"), "stratocumulus_deck": (stratus, "under_and_into")}


def cases(names, quick: bool) -> list:
    """(name, scene, views, (width, height), warmup) for each case asked."""
    valley = load_scene(DEFAULT_SCENE)
    short = (lambda n: max(3, n // 30)) if quick else (lambda n: n)
    chosen = []
    if "still" in names:
        chosen.append(("still", valley, still_views(valley, short(120)), (880, 680), SETTLE_FRAMES))
    if "orbit" in names:
        chosen.append(("orbit", valley, orbit_views(valley, short(90), 0.2), (640, 480), SETTLE_FRAMES))
    if "flythrough" in names:
        chosen.append(("flythrough", valley, path_views(valley, "flythrough", short(901)), (640, 480), 0))
    if "field" in names:
        field = dataclasses.replace(valley, clouds=cloud_field(1_200_000, 2_700))
        chosen.append(("field", field, orbit_views(field, short(120), 0.05), (640, 480), SETTLE_FRAMES))
    if "untuned" in names:
        for name, (scene, path) in untuned_scenes(valley).items():
            frames = int(scene.camera_path(path).duration * 30) + 1
            chosen.append((name, scene, path_views(scene, path, short(frames)), (640, 480), 0))
    for scenario in wang_scenarios.SCENARIOS:
        if f"wang_{scenario}" in names or "wang" in names:
            scene, _ = wang_scenarios.wang_scene(valley, scenario)
            heights = wang_scenarios.SCENARIOS[scenario][2]
            views = wang_scenarios.flight_views(short(HARRIS_FRAMES), *heights)
            chosen.append((f"wang_{scenario}", scene, views, (1024, 768), 0))
    for sky in ("cumulus_line", "popcorn_climb"):
        if sky in names or "own" in names:
            scene, views = wang_scenarios.own_scene(valley, sky, short(HARRIS_FRAMES))
            chosen.append((sky, scene, views, (640, 480), 0))
    for count in harris_figure8.COUNTS:
        for path, views_of in (("circle", harris_figure8.circle_views), ("through", harris_figure8.through_views)):
            name = f"harris_{path}_{count}"
            if name in names or "harris" in names:
                scene = harris_figure8.harris_scene(valley, count)
                chosen.append((name, scene, views_of(short(HARRIS_FRAMES)), (640, 480), SETTLE_FRAMES))
    return chosen


def summary(name: str, report: dict, warmup: int) -> list[dict]:
    reference = report["reference"]
    rows = [
        {
            "case": name,
            "mode": "full",
            "frame_ms": reference["frame_ms_mean"],
            "cloud_ms": reference["cloud_ms_mean"],
            "plan_ms": reference["plan_ms_mean"],
            "fps": 1e3 / reference["frame_ms_mean"],
        }
    ]
    for run in report["runs"]:
        rows.append(
            {
                "case": name,
                "mode": run["settings"]["mode"],
                "frame_ms": run["frame_ms_mean"],
                "cloud_ms": run["cloud_ms_mean"],
                "plan_ms": run["plan_ms_mean"],
                "fps": 1e3 / run["frame_ms_mean"],
                "cloud_speedup": run["cloud_speedup_vs_full"],
                "frame_speedup": run["speedup_vs_full"],
                "psnr_mean": run["psnr_mean"],
                "psnr_min": run["psnr_min"],
                "regenerations_per_frame": run["regenerations_per_frame"],
                "predicted_ms": run["predicted_ms_mean"],
            }
        )
    # auto against the faster of full 3D and the other modes, frame by frame of the same run
    frames = [reference["per_frame"], *(run["per_frame"] for run in report["runs"])]
    skipped = max(FIRST_COUNTED_FRAME - warmup, 0)
    counted = slice(skipped if len(frames[0]) > skipped else 0, None)  # a smoke run (`--quick`) counts them all
    frame_times = {
        row["mode"]: [frame["frame_ms"] for frame in per_frame[counted]] for row, per_frame in zip(rows, frames)
    }
    others = [mode for mode in frame_times if mode != "auto"]
    ratio, low, high = ratio_interval(frame_times["auto"], [frame_times[mode] for mode in others])
    rows[[row["mode"] for row in rows].index("auto")] |= {
        "faster_mode": min(others, key=lambda mode: np.mean(frame_times[mode])),
        "frame_vs_faster": ratio,
        "frame_vs_faster_low": low,
        "frame_vs_faster_high": high,
    }
    return rows


def plot(rows, path: Path) -> None:
    """Cloud-pass speed-up against mean PSNR, one point per mode and case."""
    plt = headless_pyplot()
    figure, axes = plt.subplots(figsize=(6.4, 4.2), dpi=120)
    for mode, marker in (("impostor", "o"), ("auto", "s")):
        points = [r for r in rows if r["mode"] == mode]
        axes.scatter(
            [r["cloud_speedup"] for r in points], [r["psnr_mean"] for r in points], marker=marker, label=mode, zorder=3
        )
        for r in points if mode == "auto" else ():
            axes.annotate(
                r["case"], (r["cloud_speedup"], r["psnr_mean"]), fontsize=7, xytext=(5, 4), textcoords="offset points"
            )
    axes.set_xscale("log")
    ticks = [2, 3, 5, 10, 20, 50, 100, 200]
    axes.set_xticks(ticks, [f"x{tick}" for tick in ticks])
    axes.minorticks_off()  # the log axis' own minor labels overprint each other
    axes.set_xlabel("cloud pass + impostor updates, speed-up over full 3D (same run)")
    axes.set_ylabel("mean PSNR against full 3D (dB)")
    axes.set_title("The level of detail on llvmpipe: error against time")
    axes.legend(fontsize=7)
    save_figure(figure, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="still,orbit,flythrough,field,untuned")
    parser.add_argument("--quick", action="store_true", help="a few frames per case: a smoke run")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--plot", type=Path)
    args = parser.parse_args()
    names = set(args.cases.split(","))
    result = {
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
        "settings": dataclasses.asdict(MODES[1]),
        "cases": {},
        "summary": [],
    }
    for name, scene, views, size, warmup in cases(names, args.quick):
        start = time.perf_counter()
        with contextlib.ExitStack() as stack:
            illumination = IlluminationCache()
            renderers = [
                stack.enter_context(FrameRenderer(*size, illumination=illumination)) for _ in range(1 + len(MODES))
            ]
            report = bench_path(renderers, scene, "", len(views), MODES, size, views=views, warmup=warmup, freeze=True)
        report["seconds"] = time.perf_counter() - start
        result["cases"][name] = report
        rows = summary(name, report, warmup)
        result["summary"] += rows
        for row in rows:
            print(
                " ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()),
                file=sys.stderr,
                flush=True,
            )
    if args.plot:
        plot([r for r in result["summary"] if r["mode"] != "full"], args.plot)
    write_report(result, args.json, summary=result["summary"])


if __name__ == "__main__":
    main()
