"""`cloudview bench SCENE --camera-path NAME --json OUT.json`: error against run time along a camera path, headless.

Each setting of the sweeps is rendered along the path beside the full-3D
reference in the same run; the report is `cloudcore.measure.benchmark.bench_path`'s,
plus the shading precompute (exact against raster).  With no --sweep, the
default settings are run.

With --workers N (or --cluster) the sweep's settings are split into N groups, each run on a worker beside its
own full-3D reference, frames taking turns there as in one process: a setting's speed-up and error are measured
against the reference drawn beside it, on the same machine at the same time, never against another worker's
(`references` lists each group's, `reference_group` says a run's).  Alone on one machine the workers share its
cores, so their times are slower than one process's; spread over a cluster's machines, each group's times are its
machine's.

`cloudview bench --suite NAME [--cases A,B]` runs a benchmark suite's cases instead (`cloudcore.cli.bench_suite`),
each by the same runner (`bench_views`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import json
import os
from contextlib import closing
from pathlib import Path

from cloudcore.cli.bench_suite import load_suite, plot_suite, run_suite
from cloudcore.cli.render import check_outputs, pixel_count, write_output
from cloudcore.cli.settings_args import SWEEPABLE, add_settings_arguments, parse_sweep, settings_from
from cloudcore.cli.workers import Job, add_workers_arguments, run_job, spread
from cloudcore.measure.benchmark import (
    bench_path,
    headless_pyplot,
    orbit_views,
    pareto_front,
    save_figure,
    shading_comparison,
    still_views,
)
from cloudcore.model.errors import SceneError
from cloudcore.model.settings import FULL_3D, RenderSettings, setting_options
from cloudcore.scenes.files import load_scene
from cloudcore.scenes.limits import frame_memory_problem

DEFAULT_FRAMES = 60
DEFAULT_SIZE = (640, 480)


def add_parser(commands) -> None:
    parser = commands.add_parser("bench", help="frame time and image error of settings against full 3D")
    parser.add_argument("scene", nargs="?", help="scene file (.toml); none with --suite")
    parser.add_argument(
        "--suite",
        metavar="NAME",
        help="run the benchmark suite NAME (one of cloudcore/resources/bench/, or a suite file NAME.toml) instead "
        "of a scene: its cases' scenes, views, sizes and settings variants are its own (docs/performance.md)",
    )
    parser.add_argument(
        "--cases", metavar="A,B", help="with --suite: the cases (or groups of cases) to run (default: the suite's)"
    )
    parser.add_argument(
        "--quick", action="store_true", help="with --suite: a thirtieth of each case's frames (a smoke run)"
    )
    views = parser.add_mutually_exclusive_group()
    views.add_argument("--camera-path", help="camera path of the scene to fly")
    views.add_argument("--still", action="store_true", help="the scene's camera, still, for --frames frames")
    views.add_argument(
        "--orbit", type=float, metavar="DEG", help="the scene's camera orbiting its look-at point DEG degrees a frame"
    )
    parser.add_argument("--json", required=True, type=Path, help="report to write")
    parser.add_argument(
        "--sweep",
        action="append",
        type=parse_sweep,
        default=[],
        help=f"NAME=V1,V2,... with NAME one of {', '.join(SWEEPABLE)}; several --sweep options combine",
    )
    parser.add_argument(
        "--frames", type=int, default=DEFAULT_FRAMES, help=f"frames spread along the path (default {DEFAULT_FRAMES})"
    )
    parser.add_argument(
        "--warmup",
        type=int,
        default=0,
        help="unmeasured frames of the first view before each run: 20 build a still view's "
        "impostors and ring (default %(default)s)",
    )
    parser.add_argument("--width", type=pixel_count, default=DEFAULT_SIZE[0])
    parser.add_argument("--height", type=pixel_count, default=DEFAULT_SIZE[1])
    parser.add_argument("--plot", type=Path, help="write the error-against-time plot here (PNG)")
    parser.add_argument("--no-shading", action="store_true", help="skip the shading precompute comparison")
    parser.add_argument(
        "--without-terrain",
        action="store_true",
        help="fly the scene without its terrain: the whole frame is then the sky and the clouds",
    )
    add_settings_arguments(parser)
    add_workers_arguments(parser, "sweep's settings, in groups each beside its own full-3D reference,")
    parser.set_defaults(run=run)


def run(args) -> int:
    check_outputs(args.json, args.plot)
    if args.suite is not None:
        return run_suite_command(args)
    for option, given in (("--cases", args.cases is not None), ("--quick", args.quick)):
        if given:
            raise SceneError(option, option.lstrip("-"), "only with --suite NAME")
    if args.scene is None:
        raise SceneError("bench", "scene", "name a scene file, or a suite with --suite NAME")
    if args.camera_path is None and not args.still and args.orbit is None:
        raise SceneError("bench", "views", "one of --camera-path NAME, --still or --orbit DEG is required")
    scene = load_scene(args.scene)
    if args.without_terrain:
        scene = dataclasses.replace(scene, terrain=None)
    if args.camera_path is not None:
        try:
            scene.camera_path(args.camera_path)
        except KeyError as error:
            raise SceneError(args.scene, "camera_paths", error.args[0]) from None
    if args.frames < 1:
        raise SceneError("--frames", "frames", f"must be >= 1, got {args.frames}")
    if args.warmup < 0:
        raise SceneError("--warmup", "warmup", f"must be >= 0, got {args.warmup}")
    if args.orbit is not None and not abs(args.orbit) < 360.0:
        raise SceneError("--orbit", "orbit", f"must be within (-360, 360) degrees a frame, got {args.orbit}")
    motion = (
        "still" if args.still else f"orbit {args.orbit:g} deg/frame" if args.orbit is not None else args.camera_path
    )
    base = settings_from(args)
    fields = [field for field, _ in args.sweep]
    settings_list = [
        settings_from(args, **dict(zip(fields, values)))
        for values in itertools.product(*(values for _, values in args.sweep))
    ] or [base]
    groups = min(args.workers or 1, len(settings_list)) if spread(args) else 1
    job = Job(
        "bench",
        BenchSettings,
        (str(args.scene), args.without_terrain, args.camera_path, args.still, args.orbit, args.frames, args.warmup)
        + ((args.width, args.height),),
        pieces=[settings_list[group::groups] for group in range(groups)],
        unit="frame",
        label=lambda index: f"settings group {index}",
        size=lambda group: (args.frames + args.warmup) * (1 + len(group)),
    )
    if spread(args):
        with closing(run_job(job, args.workers, args.cluster, args.gpus_per_task)) as reports:
            report = _merged(list(reports), groups)
    else:  # one group, here, its bar counting each frame
        from tqdm import tqdm

        with (
            tqdm(total=job.size(settings_list), unit="frame", desc="bench") as bar,
            job.make_worker(*job.arguments, progress=bar.update) as worker,
        ):
            report = worker(settings_list)
    report["path"] = motion
    report["scene"] = str(args.scene)
    report["without_terrain"] = args.without_terrain
    report["shading"] = [] if args.no_shading else shading_comparison(scene)
    write_output(args.json, lambda path: path.write_text(json.dumps(report, indent=2) + "\n"))
    reference = report["reference"]
    print(
        f"full 3D: {reference['frame_ms_mean']:.1f} ms mean, {reference['frame_ms_p95']:.1f} ms p95, "
        + _cpu_and_gpu(reference)
    )
    for run_ in report["runs"]:
        changed = {k: v for k, v in run_["settings"].items() if v != dataclasses.asdict(base)[k]}
        print(
            f"{changed or run_['settings']['mode']}: {run_['frame_ms_mean']:.1f} ms "
            f"(x{run_['speedup_vs_full']:.2f} frame, x{run_['cloud_speedup_vs_full']:.2f} clouds), "
            f"PSNR mean {run_['psnr_mean']:.2f} dB, min {run_['psnr_min']:.2f} dB, "
            f"{run_['regenerations_per_frame']:.2f} regenerations a frame, " + _cpu_and_gpu(run_)
        )
    if args.plot:
        plot_error_against_time(report, args.plot)
    print(f"wrote {args.json}" + (f" and {args.plot}" if args.plot else ""))
    return 0


def run_suite_command(args) -> int:
    """`cloudview bench --suite NAME`: every case asked of the suite, the report to --json, the plot to --plot."""
    given = [
        option
        for option, value in (
            ("SCENE", args.scene),
            ("--camera-path", args.camera_path),
            ("--still", args.still or None),
            ("--orbit", args.orbit),
            ("--sweep", args.sweep or None),
            ("--workers", args.workers),
            ("--cluster", args.cluster),
            ("--gpus-per-task", args.gpus_per_task),
            ("--frames", args.frames if args.frames != DEFAULT_FRAMES else None),
            ("--warmup", args.warmup or None),
            ("--width/--height", (args.width, args.height) if (args.width, args.height) != DEFAULT_SIZE else None),
            ("--without-terrain", args.without_terrain or None),
            ("--no-shading", args.no_shading or None),
            ("the settings options", True if settings_from(args) != RenderSettings() else None),
        )
        if value is not None
    ]
    if given:
        raise SceneError(
            "--suite", "suite", f"a suite's cases name their own scenes, views, sizes and settings: drop {given[0]}"
        )
    suite = load_suite(args.suite)
    names = None if args.cases is None else [name for name in args.cases.split(",") if name]
    cases = suite.chosen(names)  # a name no case answers to is refused before any frame
    for case in cases:
        problem = frame_memory_problem(*case.size)
        if problem is not None:
            raise SceneError(suite.source, f"cases.{case.name}.width/height", problem)
    result = run_suite(suite, names, args.quick, bench_views)
    write_output(args.json, lambda path: path.write_text(json.dumps(result, indent=2) + "\n"))
    if args.plot:
        plot_suite(result, args.plot)
    print(f"wrote {args.json}" + (f" and {args.plot}" if args.plot else ""))
    return 0


class BenchSettings:
    """A worker of `cloudcore.cli.workers`: called with a group of settings, the bench report of them beside one
    full-3D reference, frames taking turns, in this process's own GL context."""

    def __init__(
        self,
        scene_file: str,
        without_terrain: bool,
        camera_path,
        still: bool,
        orbit,
        frames,
        warmup,
        size,
        progress=None,
    ):
        """`progress(frames)` is told of each frame drawn, where one is given (in this process)."""
        self.progress = progress
        self.scene = load_scene(scene_file)
        if without_terrain:
            self.scene = dataclasses.replace(self.scene, terrain=None)
        self.path, self.frames, self.warmup, self.size = camera_path, frames, warmup, size
        self.views = (
            still_views(self.scene, frames)
            if still
            else orbit_views(self.scene, frames, orbit)
            if orbit is not None
            else None
        )

    def __call__(self, settings_list: list) -> dict:
        return bench_views(
            self.scene,
            self.views,
            settings_list,
            self.size,
            self.warmup,
            path=self.path,
            frames=self.frames,
            progress=self.progress,
        )

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        pass


def bench_views(
    scene, views, settings_list: list, size, warmup: int, path=None, frames=None, progress=None, reference=FULL_3D
) -> dict:
    """The bench's runner: `bench_path`'s report of full 3D (drawn with `reference`) and each of `settings_list`
    drawing `views` (or `frames` along the camera path `path`) at `size`, frames taking turns, each in a renderer
    of its own in this process's GL context, after `warmup` unmeasured frames; what this process set up is then
    kept out of the garbage collector's full passes (a benchmark's own process)."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from cloudcore.gl import FrameRenderer
    from cloudcore.light.illumination import IlluminationCache

    illumination = IlluminationCache()  # the clouds' light, computed once for every run
    with contextlib.ExitStack() as renderers:
        return bench_path(
            [
                renderers.enter_context(FrameRenderer(*size, illumination=illumination))
                for _ in range(1 + len(settings_list))
            ],
            scene,
            path,
            len(views) if views is not None else frames,
            settings_list,
            size,
            progress=progress,
            views=views,
            warmup=warmup,
            freeze=True,
            reference=reference,
        )


def _merged(reports: list[dict], groups: int) -> dict:
    """One report of the groups' (the settings dealt to them in turn): their runs in the sweep's order, each
    measured against its own group's reference, which `references` holds where there are several."""
    if groups == 1:
        return reports[0]
    order = sorted(
        (
            (group + groups * position, group, run)
            for group, report in enumerate(reports)
            for position, run in enumerate(report["runs"])
        ),
        key=lambda item: item[0],
    )
    return reports[0] | {
        "references": [{k: v for k, v in report["reference"].items() if k != "per_frame"} for report in reports],
        "runs": [run | {"reference_group": group} for _, group, run in order],
    }


def sweep_label(settings: dict, runs: list[dict]) -> str:
    """The settings of one run that differ between the runs, by their sweep names (its mode if none do)."""
    varying = [
        (name, option.sweep_name)
        for name, option in setting_options().items()
        if len({repr(r["settings"][name]) for r in runs}) > 1
    ]
    if not varying:
        return settings["mode"]
    return ", ".join(
        f"{sweep} {settings[name]:g}" if isinstance(settings[name], float) else f"{sweep} {settings[name]}"
        for name, sweep in varying
    )


def plot_error_against_time(report: dict, path: Path) -> None:
    """One point per setting (frame time, mean absolute difference), the Pareto front joined, full 3D marked."""
    plt = headless_pyplot()
    runs = report["runs"]
    seconds = [r["frame_ms_mean"] for r in runs]
    errors = [r["mad_mean"] for r in runs]
    front = sorted(pareto_front(seconds, errors), key=lambda i: seconds[i])
    figure, axes = plt.subplots(figsize=(6.4, 4.2), dpi=120)
    axes.scatter(seconds, errors, color="tab:blue", zorder=3, label="settings")
    axes.plot(
        [seconds[i] for i in front], [errors[i] for i in front], color="tab:orange", zorder=2, label="Pareto front"
    )
    for run_, x, y in zip(runs, seconds, errors):
        axes.annotate(
            sweep_label(run_["settings"], runs), (x, y), fontsize=6, textcoords="offset points", xytext=(4, 4)
        )
    axes.axvline(report["reference"]["frame_ms_mean"], color="grey", linestyle="--", label="full 3D (error 0)")
    axes.set_xlabel("mean frame time (ms)")
    axes.set_ylabel("mean |difference| from full 3D (8-bit levels)")
    axes.set_title(f"{Path(report['scene']).name}, path {report['path']}, {report['width']}x{report['height']}")
    axes.legend(fontsize=7)
    save_figure(figure, path)


def _cpu_and_gpu(summary: dict) -> str:
    """A run's mean CPU time a frame, its GPU time per pass and the frames sorted each way, as the bench prints
    them."""
    passes = ", ".join(f"{name.replace('_', ' ')} {ms:.1f}" for name, ms in summary["gpu_ms_by_pass"].items())
    ways = ", ".join(f"{way} {frames}" for way, frames in sorted(summary["splat_order_frames"].items()) if way)
    return f"CPU {summary['cpu_ms_mean']:.1f} ms, GPU {summary['gpu_ms_mean']:.1f} ms ({passes}), sorted on: {ways}"
