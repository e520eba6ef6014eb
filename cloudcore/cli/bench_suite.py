"""`cloudview bench --suite NAME [--cases A,B]`: the benchmark suite, its cases as data, run by one runner.

A suite is a TOML file, `cloudcore/resources/bench/NAME.toml` (or any file named by its path): its `[defaults]`
and its `[[cases]]`, each case a scene (a scene file, and a sky made from a seed over it:
`cloudcore.measure.bench_skies`), its views (still, orbiting, a camera path, or a sky's own flight), a size, the
settings variants drawn beside the full-3D reference, the unmeasured warm-up frames and the frames measured.
Every key is checked when the suite is read, before any frame (how to add a case:
docs/architecture.md#how-to-add-).  Each case is one run of `cloudcore.measure.benchmark.bench_path`
(`cloudcore.cli.bench.bench_views`): the reference and the variants take turns frame by frame, each variant's
frame compared with the reference's (PSNR); the report gives each variant's time over the reference's with its
95% interval (`ratio_interval`), and auto's over the faster of the others where the case asks.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

from cloudcore.measure import bench_skies
from cloudcore.measure.benchmark import (
    headless_pyplot,
    machine,
    orbit_views,
    path_views,
    ratio_interval,
    save_figure,
    still_views,
)
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Scene, Wind
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.model.toml_table import Table, field_error, read_toml
from cloudcore.resources import resource_path
from cloudcore.scenes.files import load_scene, read_wind, settings_overrides

#: the suites shipped, one TOML file each
SUITES_FOLDER = resource_path("bench")
#: how a case's views are made (`case_views`)
VIEWS = ("still", "orbit", "path", "harris_circle", "harris_through", "sky")
#: the skies a case may draw over its scene file, with the keys each takes (`case_scene`)
SKIES = {
    "harris": ("count",),
    "wang": ("scenario",),
    "own": ("name",),
    "untuned": ("name",),
    "particle_field": ("particles", "per_cloud"),
}
#: a case's keys; every one may also be given in the suite's [defaults]
CASE_KEYS = (
    "name",
    "group",
    "scene",
    "sky",
    "wind",
    "without_terrain",
    "views",
    "orbit_deg",
    "camera_path",
    "times_s",
    "frames",
    "fps",
    "seconds_a_frame",
    "width",
    "height",
    "warmup",
    "reference",
    "variants",
    "auto_vs_faster",
    "first_counted_frame",
)
SUITE_KEYS = ("description", "default_cases", "defaults", "cases")
MAX_FRAMES = 100_000
MAX_SIDE = 8192


@dataclasses.dataclass(frozen=True)
class Case:
    """One benchmark case, as read from its suite: everything needed to make its scene, views and runs."""

    name: str
    group: str
    scene: Path
    sky: tuple  # (kind, *its values) or () for the scene file's own clouds
    wind: Wind | None  # the scene's wind instead of its file's, where the case gives one
    without_terrain: bool
    views: str
    orbit_deg: float
    camera_path: str
    times_s: tuple[float, ...]  # seconds along the camera path its frames are drawn at, in turn; () for all of it
    frames: int  # 0: `fps` frames a second of the camera path
    fps: float
    seconds_a_frame: float  # the scene clock's step a frame, whatever the views; 0: the views' own clock
    size: tuple[int, int]
    warmup: int
    reference: RenderSettings  # full 3D, as shipped unless the case compares ways of drawing every particle
    variants: tuple[RenderSettings, ...]
    auto_vs_faster: bool
    first_counted_frame: int


@dataclasses.dataclass(frozen=True)
class Suite:
    name: str
    source: str
    description: str
    default_cases: tuple[str, ...]
    cases: tuple[Case, ...]

    def chosen(self, names: list[str] | None) -> list[Case]:
        """The cases named (by their name or their group), in the suite's order; the suite's default ones (all
        if it names none) where `names` is None.  A name no case answers to is refused."""
        names = list(self.default_cases or [case.name for case in self.cases]) if names is None else names
        known = {case.name for case in self.cases} | {case.group for case in self.cases if case.group}
        for name in names:
            if name not in known:
                raise SceneError("--cases", "cases", f"no case or group {name!r} in suite {self.name!r}")
        return [case for case in self.cases if case.name in names or case.group in names]


def suite_names() -> list[str]:
    """The suites shipped, by name."""
    return sorted(path.stem for path in SUITES_FOLDER.glob("*.toml"))


def load_suite(name: str) -> Suite:
    """The suite `name` (shipped) or at the path `name` (ending in .toml), every case checked; a SceneError
    naming the file, the field and the problem otherwise."""
    path = Path(name) if name.endswith(".toml") else SUITES_FOLDER / f"{name}.toml"
    if not name.endswith(".toml") and name not in suite_names():
        raise SceneError("--suite", "suite", f"no suite {name!r}; the suites: {', '.join(suite_names())}")
    source = str(path)
    data = read_toml(path)
    return suite_from_dict(data, path.stem, source)


def suite_from_dict(data: dict, name: str, source: str) -> Suite:
    """A suite from its parsed TOML (`load_suite`), every case checked."""
    top = Table(source, "", data)
    top.reject_unknown(SUITE_KEYS)
    defaults = top.table("defaults", lambda t: t) or Table(source, "defaults", {})
    defaults.reject_unknown(tuple(key for key in CASE_KEYS if key != "name"))
    tables = top.tables("cases")
    if not tables:
        top.fail("cases", "a suite needs at least one [[cases]]")
    cases = tuple(_case(table, defaults) for table in tables)
    seen = set()
    for table, case in zip(tables, cases):
        if case.name in seen:
            table.fail("name", f"{case.name!r} names two cases")
        seen.add(case.name)
    default_cases = top.raw("default_cases", [])
    if not (isinstance(default_cases, list) and all(isinstance(n, str) for n in default_cases)):
        top.fail("default_cases", f"expected a list of case or group names, got {default_cases!r}")
    known = seen | {case.group for case in cases}
    for default in default_cases:
        if default not in known:
            top.fail("default_cases", f"no case or group {default!r}")
    return Suite(name, source, top.string("description", ""), tuple(default_cases), cases)


def _case(t: Table, defaults: Table) -> Case:
    """One [[cases]] table, its missing keys taken from [defaults]."""
    t.reject_unknown(CASE_KEYS)
    merged = Table(t.source, t.field, defaults.data | t.data)
    name = merged.string("name")
    views = merged.string("views", choices=VIEWS)
    sky = merged.table("sky", _sky) or ()
    if views in ("harris_circle", "harris_through") and sky[:1] != ("harris",):
        merged.fail("views", f"{views!r} flies Harris's field: needs sky.kind = 'harris'")
    if views == "sky" and sky[:1] not in (("wang",), ("own",)):
        merged.fail("views", "'sky' flies a sky's own flight: needs sky.kind 'wang' or 'own'")
    if views == "path" and not merged.has("camera_path"):
        merged.fail("camera_path", "views = 'path' needs the name of a camera path of the scene")
    if views == "orbit" and not merged.has("orbit_deg"):
        merged.fail("orbit_deg", "views = 'orbit' needs the degrees a frame")
    if merged.has("frames") == merged.has("fps"):
        merged.fail("frames", "give either frames or fps (frames along the whole camera path, so many a second)")
    if merged.has("fps") and views != "path":
        merged.fail("fps", "only a camera path's views are counted a second")
    if merged.has("times_s") and (views != "path" or merged.has("fps")):
        merged.fail("times_s", "instants of a camera path (views = 'path'), drawn in turn for `frames` frames")
    times = merged.raw("times_s", [])
    if not (isinstance(times, list) and all(_is_time(t) for t in times)):
        merged.fail("times_s", f"expected a list of seconds >= 0, got {times!r}")
    variants = merged.raw("variants", [])
    if not isinstance(variants, list) or not variants:
        merged.fail("variants", "expected a non-empty list of settings tables ({ mode = 'auto' }, ...)")
    settings = tuple(
        _variant(Table(t.source, f"{merged.path('variants')}[{i}]", item)) for i, item in enumerate(variants)
    )
    reference = merged.table("reference", _variant) or FULL_3D
    if reference.mode != "full":
        merged.fail("reference", f"the reference draws every particle: mode must be 'full', got {reference.mode!r}")
    auto_vs_faster = merged.boolean("auto_vs_faster")
    if auto_vs_faster and sum(s.mode == "auto" for s in settings) != 1:
        merged.fail("auto_vs_faster", "needs exactly one variant in mode 'auto'")
    without_terrain = merged.boolean("without_terrain")
    scene = merged.string("scene", "valley.toml")
    return Case(
        name=name,
        group=merged.string("group", ""),
        scene=Path(scene) if "/" in scene else resource_path("scenes", scene),
        sky=sky,
        wind=merged.table("wind", read_wind),
        without_terrain=without_terrain,
        views=views,
        orbit_deg=merged.number("orbit_deg", 0.0, low=-360.0, high=360.0, low_open=True),
        camera_path=merged.string("camera_path", ""),
        times_s=tuple(float(t) for t in times),
        frames=merged.integer("frames", 0, low=1 if merged.has("frames") else 0, high=MAX_FRAMES),
        fps=merged.number("fps", 0.0, low=0.0, high=1000.0, low_open=merged.has("fps")),
        seconds_a_frame=merged.number("seconds_a_frame", 0.0, low=0.0, high=86_400.0),
        size=(merged.integer("width", 640, low=1, high=MAX_SIDE), merged.integer("height", 480, low=1, high=MAX_SIDE)),
        warmup=merged.integer("warmup", 0, low=0, high=MAX_FRAMES),
        reference=reference,
        variants=settings,
        auto_vs_faster=auto_vs_faster,
        first_counted_frame=merged.integer("first_counted_frame", 0, low=0, high=MAX_FRAMES),
    )


def _is_time(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and 0.0 <= value < math.inf


def _sky(t: Table) -> tuple:
    kind = t.string("kind", choices=tuple(SKIES))
    t.reject_unknown(("kind", *SKIES[kind]))
    if kind == "harris":
        return (kind, t.integer("count", None, low=1, high=100_000))
    if kind == "wang":
        return (kind, t.string("scenario", choices=tuple(bench_skies.WANG_SCENARIOS)))
    if kind == "own":
        return (kind, t.string("name", choices=bench_skies.OWN_SKIES))
    if kind == "untuned":
        return (kind, t.string("name", choices=tuple(bench_skies.UNTUNED_SCENES)))
    return (
        kind,
        t.integer("particles", None, low=1, high=50_000_000),
        t.integer("per_cloud", None, low=1, high=1_000_000),
    )


def _variant(t: Table) -> RenderSettings:
    """A settings table: `mode` and any other RenderSettings field, each checked as a scene view's are."""
    mode = t.string("mode", "auto", choices=("full", "impostor", "auto"))
    overrides = dict(settings_overrides(Table(t.source, t.field, {k: v for k, v in t.data.items() if k != "mode"})))
    try:
        return RenderSettings(mode=mode, **overrides)
    except ValueError as error:  # a rule between fields, or a range: RenderSettings names the field in its words
        raise field_error(t.source, t.field, str(error)) from None


def case_scene(case: Case) -> Scene:
    """The case's scene: its scene file, the sky drawn over it where it names one."""
    scene = load_scene(case.scene)
    if case.without_terrain:
        scene = dataclasses.replace(scene, terrain=None)
    if case.wind is not None:
        scene = dataclasses.replace(scene, wind=case.wind)
    kind, *values = case.sky or ("",)
    if kind == "harris":
        return bench_skies.harris_scene(scene, *values)
    if kind == "wang":
        return bench_skies.wang_scene(scene, *values)
    if kind == "own":
        return bench_skies.own_scene(scene, *values)
    if kind == "untuned":
        return bench_skies.untuned_scene(scene, *values)
    if kind == "particle_field":
        return dataclasses.replace(scene, clouds=bench_skies.particle_field(*values))
    return scene


def check_camera_paths(suite: Suite, cases: list[Case]) -> None:
    """Before any frame: every case flying a camera path names one its scene has (each scene file read once)."""
    files: dict = {}
    for case in cases:
        if case.views != "path":
            continue
        if case.sky[:1] == ("untuned",):
            names = {bench_skies.UNTUNED_SCENES[case.sky[1]]}
        else:
            if case.scene not in files:
                files[case.scene] = {path.name for path in load_scene(case.scene).camera_paths}
            names = files[case.scene]
        if case.camera_path not in names:
            raise field_error(
                suite.source,
                f"cases.{case.name}.camera_path",
                f"no camera path {case.camera_path!r} in its scene; it has: {', '.join(sorted(names)) or 'none'}",
            )


def case_frames(case: Case, scene: Scene) -> int:
    """How many frames the case measures: its own count, or `fps` a second of its camera path."""
    if case.frames:
        return case.frames
    return int(scene.camera_path(case.camera_path).duration * case.fps) + 1


def case_views(case: Case, scene: Scene, quick: bool = False) -> list:
    """(scene clock, camera) of each frame the case measures, the clock `seconds_a_frame` a frame where the case
    gives it; `quick`: a thirtieth of them, at least 3 (a smoke run, not numbers to quote)."""
    views = _views(case, scene, quick)
    if case.seconds_a_frame:
        return [(frame * case.seconds_a_frame, camera) for frame, (_, camera) in enumerate(views)]
    return views


def _views(case: Case, scene: Scene, quick: bool) -> list:
    frames = case_frames(case, scene)
    frames = max(3, frames // 30) if quick else frames
    kind, *values = case.sky or ("",)
    if case.views == "still":
        return still_views(scene, frames)
    if case.views == "orbit":
        return orbit_views(scene, frames, case.orbit_deg)
    if case.views == "path":
        return path_views(scene, case.camera_path, frames, case.times_s)
    if case.views == "harris_circle":
        return bench_skies.circle_views(frames)
    if case.views == "harris_through":
        return bench_skies.through_views(frames)
    if kind == "wang":
        return bench_skies.wang_flight_views(values[0], frames)
    return bench_skies.own_views(values[0], frames)


def built_cases(suite_name: str, names: list[str] | None, quick: bool = False) -> list:
    """(name, scene, views, (width, height), warmup) of each case asked of the suite: what the scripts that
    replay or time a case's frames their own way take (`scripts/bench_plan.py`...)."""
    suite = load_suite(suite_name)
    cases = suite.chosen(names)
    check_camera_paths(suite, cases)
    built = []
    for case in cases:
        scene = case_scene(case)
        built.append((case.name, scene, case_views(case, scene, quick), case.size, case.warmup))
    return built


def run_suite(suite: Suite, names: list[str] | None, quick: bool, bench_views) -> dict:
    """Every case asked, one after the other, each by `bench_views(scene, views, variants, size, warmup,
    reference=)` (the bench's runner: full 3D and the variants taking turns frame by frame); the report: each
    case's and the summary's rows."""
    cases = suite.chosen(names)
    check_camera_paths(suite, cases)
    result = {
        "suite": suite.name,
        "source": suite.source,
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
        "quick": quick,
        "cases": {},
        "summary": [],
    }
    for case in cases:
        start = time.perf_counter()
        scene = case_scene(case)
        views = case_views(case, scene, quick)
        report = bench_views(scene, views, list(case.variants), case.size, case.warmup, reference=case.reference)
        report["seconds"] = time.perf_counter() - start
        report["warmup"] = case.warmup
        result["cases"][case.name] = report
        rows = summary_rows(case, report)
        result["summary"] += rows
        for row in rows:
            print(row_line(row), file=sys.stderr, flush=True)
    return result


def row_line(row: dict) -> str:
    """A summary row as the suite prints it: the mean frame, and for a variant its time over the reference's (95%
    interval), its PSNR, and auto's over the faster of the others where measured."""
    line = f"{row['case']} {row['variant']}: {row['frame_ms']:.1f} ms"
    if "psnr_mean" in row:
        line += (
            f", x{row['frame_ms_vs_reference']:.3f} [{row['frame_ms_vs_reference_low']:.3f}, "
            f"{row['frame_ms_vs_reference_high']:.3f}] of full 3D's, PSNR {row['psnr_mean']:.1f} dB "
            f"(min {row['psnr_min']:.1f})"
        )
    if "frame_vs_faster" in row:
        line += (
            f", x{row['frame_vs_faster']:.3f} [{row['frame_vs_faster_low']:.3f}, {row['frame_vs_faster_high']:.3f}] "
            f"of the faster ({row['faster_mode']})"
        )
    return line


def variant_label(settings: dict) -> str:
    """A variant by what sets it apart from the default settings (its mode, and any other field changed)."""
    defaults = dataclasses.asdict(RenderSettings())
    changed = [f"{k}={v}" for k, v in settings.items() if k != "mode" and v != defaults[k]]
    return " ".join([settings["mode"], *changed])


def summary_rows(case: Case, report: dict) -> list[dict]:
    """One row for the reference and one per variant: mean times, PSNR, and each variant's frame, world and cloud
    time (`cloud_ms`: the cloud pass and the impostor updates; `cloud_work_ms`: those and the plan) over the
    reference's with its 95% interval, counted from the case's `first_counted_frame` (the warm-up frames count);
    where the case asks, auto's frame over the faster of the others."""
    reference = report["reference"]
    runs = report["runs"]
    skipped = max(case.first_counted_frame - case.warmup, 0)
    counted = slice(skipped if len(reference["per_frame"]) > skipped else 0, None)  # a quick run counts them all

    def per_frame(run, key):
        if key == "cloud_ms":  # the clouds' drawing: their pass and their impostors' updates
            return [f["cloud_ms"] + f.get("impostor_update_ms", 0.0) for f in run["per_frame"][counted]]
        if key == "cloud_work_ms":  # and their plan too: issue 51's "cloud work", all a frame's clouds cost it
            return [f["plan_ms"] + f["cloud_ms"] + f.get("impostor_update_ms", 0.0) for f in run["per_frame"][counted]]
        return [f[key] for f in run["per_frame"][counted]]

    def row(run, label):
        return {
            "case": case.name,
            "variant": label,
            "mode": run["settings"]["mode"] if "settings" in run else "full",
            "width": report["width"],
            "height": report["height"],
            "frames": len(run["per_frame"]),
            "frame_ms": run["frame_ms_mean"],
            "world_ms": run["world_ms_mean"],
            "cloud_ms": run["cloud_ms_mean"],
            "plan_ms": run["plan_ms_mean"],
            "cloud_gpu_ms": run["gpu_ms_by_pass"]["clouds"],
            "light_ms": float(np.mean([f.get("illumination_ms", 0.0) for f in run["per_frame"]])),
            "fps": 1e3 / run["frame_ms_mean"],
        }

    rows = [row(reference, "reference (" + variant_label(reference["settings"]).replace("full", "full 3D", 1) + ")")]
    labels = [variant_label(run["settings"]) for run in runs]
    for run, label in zip(runs, labels):
        ratios = {}
        for key in ("frame_ms", "world_ms", "cloud_ms", "cloud_work_ms", "cloud_gpu_ms"):
            ratio, low, high = ratio_interval(per_frame(run, key), [per_frame(reference, key)])
            ratios |= {f"{key}_vs_reference": ratio, f"{key}_vs_reference_low": low, f"{key}_vs_reference_high": high}
        rows.append(
            row(run, label)
            | {
                "frame_speedup": run["speedup_vs_full"],
                "cloud_speedup": run["cloud_speedup_vs_full"],
                "psnr_mean": run["psnr_mean"],
                "psnr_min": run["psnr_min"],
                "regenerations_per_frame": run["regenerations_per_frame"],
                # the largest error an impostor or the ring was drawn with, in tolerances
                "accepted_error_max": max(f.get("accepted_error_tolerances", 0.0) for f in run["per_frame"]),
                "predicted_ms": run["predicted_ms_mean"],
            }
            | ratios
        )
    if case.auto_vs_faster:
        everyone = [reference, *runs]
        auto = next(i for i, run in enumerate(everyone) if run.get("settings", {}).get("mode") == "auto")
        others = [i for i in range(len(everyone)) if i != auto]
        times = [per_frame(run, "frame_ms") for run in everyone]
        ratio, low, high = ratio_interval(times[auto], [times[i] for i in others])
        rows[auto] |= {
            "faster_mode": rows[min(others, key=lambda i: np.mean(times[i]))]["variant"],
            "frame_vs_faster": ratio,
            "frame_vs_faster_low": low,
            "frame_vs_faster_high": high,
        }
    return rows


def plot_suite(result: dict, path: Path) -> None:
    """Cloud work's speed-up over full 3D against mean PSNR, one point per variant and case, marked by mode."""
    plt = headless_pyplot()
    figure, axes = plt.subplots(figsize=(6.4, 4.2), dpi=120)
    variants = [row for row in result["summary"] if "psnr_mean" in row]
    for mode, marker in (("full", "^"), ("impostor", "o"), ("auto", "s")):
        points = [row for row in variants if row["mode"] == mode]
        if not points:
            continue
        axes.scatter(
            [r["cloud_speedup"] for r in points], [r["psnr_mean"] for r in points], marker=marker, label=mode, zorder=3
        )
        for r in points:
            changed = r["variant"].partition(" ")[2]  # what besides its mode sets the variant apart
            axes.annotate(
                f"{r['case']} {changed}".strip(),
                (r["cloud_speedup"], r["psnr_mean"]),
                fontsize=6,
                xytext=(5, 4),
                textcoords="offset points",
            )
    axes.set_xscale("log")
    speedups = [r["cloud_speedup"] for r in variants]
    ticks = [t for t in (0.5, 1, 2, 3, 5, 10, 20, 50, 100, 200) if min(speedups) / 1.5 <= t <= max(speedups) * 1.5]
    axes.set_xticks(ticks, [f"x{tick:g}" for tick in ticks])
    axes.minorticks_off()  # the log axis' own minor labels overprint each other
    axes.set_xlabel("cloud pass + impostor updates, speed-up over full 3D (same run)")
    axes.set_ylabel("mean PSNR against full 3D (dB)")
    axes.set_title(f"suite {result['suite']} on {result['machine']}: error against time")
    axes.legend(fontsize=7)
    save_figure(figure, path)
