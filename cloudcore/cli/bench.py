"""`cloudview bench SCENE --camera-path NAME --json OUT.json`: error against run time along a camera path, headless.

Each setting of the sweeps is rendered along the path beside the full-3D
reference in the same run; the report is `cloudcore.measure.benchmark.bench_path`'s,
plus the shading precompute (exact against raster).  With no --sweep, the
default settings are run.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import json
import os
from pathlib import Path

from cloudcore.cli.render import check_outputs, pixel_count, write_output
from cloudcore.cli.settings_args import SWEEPABLE, add_settings_arguments, parse_sweep, settings_from
from cloudcore.errors import SceneError
from cloudcore.measure.benchmark import (
    bench_path,
    headless_pyplot,
    orbit_views,
    pareto_front,
    save_figure,
    shading_comparison,
    still_views,
)
from cloudcore.scenefile import load_scene
from cloudcore.settings import setting_options


def add_parser(commands) -> None:
    parser = commands.add_parser("bench", help="frame time and image error of settings against full 3D")
    parser.add_argument("scene", help="scene file (.toml)")
    views = parser.add_mutually_exclusive_group(required=True)
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
    parser.add_argument("--frames", type=int, default=60, help="frames spread along the path (default 60)")
    parser.add_argument(
        "--warmup",
        type=int,
        default=0,
        help="unmeasured frames of the first view before each run: 20 build a still view's "
        "impostors and ring (default %(default)s)",
    )
    parser.add_argument("--width", type=pixel_count, default=640)
    parser.add_argument("--height", type=pixel_count, default=480)
    parser.add_argument("--plot", type=Path, help="write the error-against-time plot here (PNG)")
    parser.add_argument("--no-shading", action="store_true", help="skip the shading precompute comparison")
    parser.add_argument(
        "--without-terrain",
        action="store_true",
        help="fly the scene without its terrain: the whole frame is then the sky and the clouds",
    )
    add_settings_arguments(parser)
    parser.set_defaults(run=run)


def run(args) -> int:
    check_outputs(args.json, args.plot)
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
    views = (
        still_views(scene, args.frames)
        if args.still
        else orbit_views(scene, args.frames, args.orbit)
        if args.orbit is not None
        else None
    )
    motion = (
        "still" if args.still else f"orbit {args.orbit:g} deg/frame" if args.orbit is not None else args.camera_path
    )
    base = settings_from(args)
    fields = [field for field, _ in args.sweep]
    settings_list = [
        settings_from(args, **dict(zip(fields, values)))
        for values in itertools.product(*(values for _, values in args.sweep))
    ] or [base]

    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from tqdm import tqdm

    from cloudcore.gl import FrameRenderer
    from cloudcore.light.illumination import IlluminationCache

    with (
        contextlib.ExitStack() as renderers,
        tqdm(total=(args.frames + args.warmup) * (1 + len(settings_list)), unit="frame", desc="bench") as bar,
    ):
        illumination = IlluminationCache()  # the clouds' light, computed once for every run
        report = bench_path(
            [
                renderers.enter_context(FrameRenderer(args.width, args.height, illumination=illumination))
                for _ in range(1 + len(settings_list))
            ],
            scene,
            args.camera_path,
            args.frames,
            settings_list,
            (args.width, args.height),
            progress=bar.update,
            views=views,
            warmup=args.warmup,
            freeze=True,
        )
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
