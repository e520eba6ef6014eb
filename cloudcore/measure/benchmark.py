"""Error against run time: a camera path rendered in full 3D and in each setting, side by side in one run.

`bench_path` takes renderers with `render(scene, camera=, settings=, time_s=) ->
(sRGB image, stats)` (in practice `cloudcore.gl.FrameRenderer`), one for the
full-3D reference and one per setting, so this module stays free of OpenGL.
They take turns frame by frame (`turns`), and every setting's frame is compared
with the reference's.  Run one after the other, the ratio of two runs moved with
the machine: on the 2-core llvmpipe machine the same flythrough's full 3D took
88.7 to 123 ms on one day, and its speedup went with it; frame by frame, both
see the same machine.  PSNR
of identical frames is reported as `PSNR_CAP_DB` (JSON has no infinity).  The
report keys are a contract (issue 7): extend, do not rename.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import platform
import subprocess
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

from cloudcore.light.illumination import illuminate_clouds
from cloudcore.light.lighting import active_lights, scene_lights
from cloudcore.maths.paths import camera_on_path, frame_times
from cloudcore.measure.imagecompare import compare
from cloudcore.model.scene import Scene
from cloudcore.model.settings import FULL_3D
from cloudcore.runtime.collector import freeze_what_is_set_up
from cloudcore.world.navigation import orbited

PSNR_CAP_DB = 100.0


def resident_memory_bytes() -> int:
    """This process's resident memory now, from /proc (Linux): on llvmpipe "GPU" memory is process memory too."""
    with open("/proc/self/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS line in /proc/self/status")


def path_views(scene: Scene, path_name: str, frames: int, times_s=()) -> list:
    """(scene clock in seconds, camera) of `frames` frames spread along the path, or at the seconds along it
    `times_s` in turn where given (a few views drawn again and again)."""
    path = scene.camera_path(path_name)
    times = [times_s[frame % len(times_s)] for frame in range(frames)] if times_s else frame_times(path, frames)
    return [(path.keys[0, 0] + t, camera_on_path(path, t, scene.camera.fov_y_deg)) for t in times]


def still_views(scene: Scene, frames: int) -> list:
    """The scene's own camera, `frames` times: what a still camera costs once the caches are warm."""
    return [(0.0, scene.camera)] * frames


def orbit_views(scene: Scene, frames: int, degrees_per_frame: float) -> list:
    """The scene's camera orbiting its look-at point by `degrees_per_frame` a frame (a slow pan round)."""
    views, camera = [], scene.camera
    for _ in range(frames):
        views.append((0.0, camera))
        camera = orbited(camera, degrees_per_frame)
    return views


def turns(runs: int, frames: int) -> list[list[int]]:
    """The order the `runs` render in, frame by frame: each follows each other run about equally often and never
    itself, and takes each place in the frame about equally often (greedily, the least used pair and place first).

    A run's frame time depends on the run before it: with the order reversed every other frame, three renderers
    of the same settings on the default view measured the one at an end (after itself every other frame) slower
    than the one in the middle in each of 6 runs of 40 frames, by 0.5 to 11% (4.4% on average; in the level of
    detail's bench, impostor mode had the middle and auto an end).
    """
    pairs: dict = {}  # (run before, run) -> times
    places: dict = {}  # (run, place in the frame) -> times
    before, order = None, []
    for _ in range(frames):
        left, frame = list(range(runs)), []
        for place in range(runs):
            run = min(left, key=lambda r: (r == before, pairs.get((before, r), 0) + places.get((r, place), 0), r))
            pairs[before, run] = pairs.get((before, run), 0) + 1
            places[run, place] = places.get((run, place), 0) + 1
            before = run
            frame.append(run)
            left.remove(run)
        order.append(frame)
    return order


def _interleaved_rows(
    renderers,
    scene: Scene,
    views,
    settings_list,
    progress=None,
    warmup: int = 0,
    freeze: bool = False,
    reference=FULL_3D,
) -> list:
    """Per renderer (the reference's first, in full 3D), one row a frame: its statistics and, but for the
    reference's, its error against the reference's image of that frame."""
    runs = list(zip(renderers, [reference, *settings_list]))
    for renderer, settings in runs:
        for _ in range(warmup):  # unmeasured frames at the first view: caches built, the ring faded in
            renderer.render(scene, camera=views[0][1], settings=settings, time_s=views[0][0])
            if progress is not None:
                progress()
    if freeze:  # a full collection is a 70 ms stall in whichever run's frame sets it off
        freeze_what_is_set_up()
    rows = [[] for _ in runs]
    for frame, ((time_s, camera), order) in enumerate(zip(views, turns(len(runs), len(views)))):
        images = [None] * len(runs)
        for index in order:
            renderer, settings = runs[index]
            images[index], stats = renderer.render(scene, camera=camera, settings=settings, time_s=time_s)
            numbers = {k: v for k, v in stats.as_dict().items() if isinstance(v, (int, float))}
            # which ways the frame took: what a GPU's "auto" trials kept is read off the report
            ways = {"splat_order": stats.splat_order, "compositing": stats.compositing}
            rows[index].append({"frame": frame, **numbers, **ways})
            if progress is not None:
                progress()
        for index in range(1, len(runs)):
            difference = compare(images[index], images[0])
            rows[index][-1] |= {"psnr_db": min(difference.psnr_db, PSNR_CAP_DB), "mad": difference.mean_abs}
    return rows


def _summary(rows) -> dict:
    times = np.array([r["frame_ms"] for r in rows])
    # the GPU's own clock per pass (GL_TIMESTAMP, `cloudcore.gl.pass_clock`): where a GPU spends the frame
    gpu_ms_by_pass = {
        name: float(np.mean([r[key] for r in rows]))
        for name, key in (
            ("clouds", "cloud_gpu_ms"),
            ("impostor_updates", "impostor_update_gpu_ms"),
            ("world", "world_gpu_ms"),
        )
    }
    return {
        "frame_ms_mean": float(times.mean()),
        "frame_ms_p95": float(np.percentile(times, 95)),
        "cloud_ms_mean": float(np.mean([r["cloud_ms"] + r.get("impostor_update_ms", 0.0) for r in rows])),
        "world_ms_mean": float(np.mean([r["world_ms"] for r in rows])),
        "plan_ms_mean": float(np.mean([r.get("plan_ms", 0.0) for r in rows])),
        "cpu_ms_mean": float(np.mean([r["cpu_ms"] for r in rows])),
        "gpu_ms_mean": sum(gpu_ms_by_pass.values()),
        "gpu_ms_by_pass": gpu_ms_by_pass,
        "splat_order_frames": dict(Counter(r.get("splat_order", "") for r in rows)),
        # drawn twice: a compute-composited draw had more tile pairs than the GPU had room for (in frame_ms)
        "frames_drawn_again": int(sum(r.get("drawn_again", False) for r in rows)),
    }


def bench_path(
    renderers,
    scene: Scene,
    path_name: str,
    frames: int,
    settings_list,
    size,
    progress=None,
    views=None,
    warmup: int = 0,
    freeze: bool = False,
    reference=FULL_3D,
) -> dict:
    """The report: reference (full 3D) and one run per settings object, errors per frame and overall.

    `renderers`: one for the reference, then one per settings object, each with its own caches; they
    render frame by frame in turn.  The frames are `views` ((scene clock, camera) pairs) when given,
    else `frames` along the path; each run first renders `warmup` unmeasured frames of the first view.
    `freeze`: after those, leave what is set up out of the garbage collector's full passes, for the rest of the
    process (`cloudcore.runtime.collector`; a benchmark's own process, not a test's).  `reference`: the full-3D settings
    the reference is drawn with (a way of drawing every particle measured against another: `compositing`...).
    """
    if reference.mode != "full":
        raise ValueError(f"the reference draws every particle (mode 'full'), not {reference.mode!r}")
    if len(renderers) != 1 + len(settings_list):
        raise ValueError(f"{len(renderers)} renderers for the reference and {len(settings_list)} settings")
    views = path_views(scene, path_name, frames) if views is None else views
    for renderer in renderers:  # shading precompute, shader compiles; in full 3D, no impostor made ahead
        renderer.render(scene, camera=views[0][1], settings=FULL_3D)
    reference_rows, *rows_of_runs = _interleaved_rows(
        renderers, scene, views, settings_list, progress, warmup, freeze, reference
    )
    reference = {
        "mode": "full",
        "settings": dataclasses.asdict(reference),
        **_summary(reference_rows),
        "per_frame": reference_rows,
    }
    runs = []
    for settings, rows in zip(settings_list, rows_of_runs):
        psnr = np.array([r["psnr_db"] for r in rows])
        summary = _summary(rows)
        runs.append(
            {
                "settings": dataclasses.asdict(settings),
                **summary,
                "speedup_vs_full": reference["frame_ms_mean"] / summary["frame_ms_mean"],
                "cloud_speedup_vs_full": reference["cloud_ms_mean"] / summary["cloud_ms_mean"],
                "psnr_mean": float(psnr.mean()),
                "psnr_min": float(psnr.min()),
                "mad_mean": float(np.mean([r["mad"] for r in rows])),
                "regenerations": int(sum(r.get("impostors_regenerated", 0) for r in rows)),
                "regenerations_per_frame": float(np.mean([r.get("impostors_regenerated", 0) for r in rows])),
                "predicted_ms_mean": float(np.mean([r.get("predicted_ms", 0.0) for r in rows])),
                "frames_below_30_db": int(np.sum(psnr < 30.0)),
                "texture_bytes_max": int(max(r.get("texture_bytes", 0) for r in rows)),
                "per_frame": rows,
            }
        )
    return {
        "scene": scene.description or "",
        "path": path_name,
        "width": size[0],
        "height": size[1],
        "frames": frames,
        "reference": reference,
        "runs": runs,
    }


def shading_comparison(scene: Scene, resolutions=(32, 48, 96), repeat: int = 1) -> list[dict]:
    """Seconds and error of raster shading against exact, per active light (best of `repeat`)."""
    lights, _ = scene_lights(scene.lighting)
    rows = []
    for index, light in enumerate(active_lights(lights)):
        exact_s, exact = _timed_shading(scene, light, "exact", repeat)
        rows.append(
            {
                "light": index,
                "method": "exact",
                "seconds": exact_s,
                "particles": len(exact),
                "max_abs_error_vs_exact": 0.0,
                "mean_abs_error_vs_exact": 0.0,
            }
        )
        for resolution in resolutions:
            seconds, raster = _timed_shading(scene, light, "raster", repeat, resolution)
            error = np.abs(raster - exact)
            rows.append(
                {
                    "light": index,
                    "method": f"raster-{resolution}",
                    "seconds": seconds,
                    "particles": len(raster),
                    "max_abs_error_vs_exact": float(error.max(initial=0.0)),
                    "mean_abs_error_vs_exact": float(error.mean()) if error.size else 0.0,
                }
            )
    return rows


def _timed_shading(scene: Scene, light, method: str, repeat: int, resolution: int | None = None):
    best, result = np.inf, None
    options = {} if resolution is None else {"resolution": resolution}
    for _ in range(max(repeat, 1)):
        start = time.perf_counter()
        result = illuminate_clouds(scene.clouds, scene.shading, (light,), method, **options)
        best = min(best, time.perf_counter() - start)
    return best, (np.concatenate(result)[:, 0] if result else np.zeros(0))


def pareto_front(seconds, errors) -> list[int]:
    """Indices of the points no other point beats in both time and error (lower is better in both)."""
    points = list(zip(seconds, errors))
    return [
        i
        for i, (t, e) in enumerate(points)
        if not any((t2 <= t and e2 <= e) and (t2 < t or e2 < e) for t2, e2 in points)
    ]


#: frames per block of `ratio_interval`'s bootstrap: llvmpipe's slow phases last several frames (a still view's
#: identical frames' world pass doubles in runs of a few: docs/performance.md, "How we measure"), so single frames
#: are not independent
BOOTSTRAP_BLOCK_FRAMES = 10


def ratio_interval(numerator, denominators, resamples: int = 4000, seed: int = 0) -> tuple[float, float, float]:
    """(ratio, low, high): the mean of `numerator` over the lowest mean of `denominators` (per-frame times of
    runs measured side by side, frame i of each in the same turn), and its 95% interval.

    The interval is a circular moving-block bootstrap (blocks of `BOOTSTRAP_BLOCK_FRAMES`) that resamples the
    same frames of every run, so what the machine did to a frame falls on both sides of the ratio; which
    denominator is the lowest is chosen again in each resample, as the comparison "against the faster" asks.
    """
    if not denominators or len({len(run) for run in (numerator, *denominators)}) != 1 or not len(numerator):
        raise ValueError("a ratio needs a numerator and at least one denominator, each of the same frames")
    runs = np.array([numerator, *denominators], dtype=np.float64)
    frames = runs.shape[1]

    def ratios(sums):
        return sums[0] / np.maximum(np.min(sums[1:], axis=0), 1e-300)

    block = min(BOOTSTRAP_BLOCK_FRAMES, frames)
    starts = np.random.default_rng(seed).integers(0, frames, size=(resamples, -(-frames // block)))
    picked = ((starts[:, :, None] + np.arange(block)) % frames).reshape(resamples, -1)[:, :frames]
    sampled = ratios(runs[:, picked].sum(axis=2))
    low, high = np.percentile(sampled, [2.5, 97.5])
    return float(ratios(runs.sum(axis=1))), float(low), float(high)


def machine() -> str:
    """The processor the numbers were measured on, for a report."""
    return platform.processor() or platform.machine()


@contextlib.contextmanager
def revision_trees(revisions: dict[str, str], checkout: Path):
    """{name: path} of a temporary git worktree of each of `revisions` ({name: git revision}) of `checkout`, for a
    benchmark to run a revision's `cloudcore` beside this tree's (on a child process's PYTHONPATH); removed on
    leaving."""
    with tempfile.TemporaryDirectory() as folder:
        trees = {}
        try:
            for name, revision in revisions.items():
                trees[name] = Path(folder) / name
                subprocess.run(
                    ["git", "worktree", "add", "--detach", str(trees[name]), revision],
                    cwd=checkout,
                    check=True,
                    capture_output=True,
                )
            yield trees
        finally:
            for tree in trees.values():
                subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=checkout, check=False)


def tree_workers(command: list[str], trees: dict) -> dict:
    """{name: process} of `command` (a worker's, a list) run once per tree of `trees` ({name: path}), each over its
    tree's `cloudcore` (its PYTHONPATH and working folder), talking over its stdin and stdout as text."""
    return {
        name: subprocess.Popen(
            [*command, "--worker", str(tree)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ, "PYTHONPATH": str(tree)},
            cwd=tree,
        )
        for name, tree in trees.items()
    }


def headless_pyplot():
    """matplotlib's pyplot on the Agg backend (no display, no GUI toolkit), imported only when a plot is asked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(figure, path: Path) -> None:
    """Lay out `figure`, write it to `path` (folders made as needed) and free it."""
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    headless_pyplot().close(figure)


def write_report(report: dict, path: Path | None, summary=None) -> None:
    """Print `summary` (by default the report) as JSON and write the whole report to `path` (if given)."""
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report if summary is None else summary, indent=2))
