"""The benchmark suite (`cloudview bench --suite NAME`): its cases read and checked as data, a tiny case run end to
end, bad suites and cases refused in one line."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cloudcore.cli.bench_suite import case_scene, case_views, load_suite, suite_from_dict, suite_names
from cloudcore.measure import bench_skies
from cloudcore.model.errors import SceneError

TINY_SUITE = """
description = "a tiny suite: a few frames at 64x48"
[defaults]
width = 64
height = 48
variants = [{ mode = "impostor" }, { mode = "auto", tolerance_deg = 2.0 }]
auto_vs_faster = true
first_counted_frame = 2
[[cases]]
name = "tiny_still"
views = "still"
frames = 4
warmup = 1
[[cases]]
name = "tiny_harris"
group = "tiny"
sky = { kind = "harris", count = 4 }
views = "harris_through"
frames = 3
"""


def test_every_shipped_suite_loads_with_default_cases_and_scenes_that_exist():
    assert {"lod", "world", "compositing", "wind"} <= set(suite_names())
    for name in suite_names():
        suite = load_suite(name)
        assert suite.chosen(None), name
        for case in suite.cases:
            assert case.scene.is_file(), (name, case.name)


@pytest.mark.parametrize("path", sorted((Path(__file__).parents[3] / "docs" / "suites").glob("*.toml")), ids=str)
def test_the_suites_the_docs_measured_with_still_load(path):
    """docs/performance.md's tables name these files in their commands: they must stay runnable as the suites'
    keys and the scenes change."""
    suite = load_suite(str(path))
    assert suite.chosen(None), path
    for case in suite.cases:
        assert case.scene.is_file(), (path.name, case.name)


def test_the_lod_suite_holds_harris_figure_8_and_wang_s_scenarios_as_the_issue_asks():
    suite = load_suite("lod")
    harris = suite.chosen(["harris"])
    assert sorted((case.views, case.sky[1]) for case in harris) == sorted(
        (path, count) for path in ("harris_circle", "harris_through") for count in bench_skies.HARRIS_COUNTS
    )
    assert all(case.warmup == 20 and case.frames == 90 and case.size == (640, 480) for case in harris)
    wang = suite.chosen(["wang"])
    assert [case.sky for case in wang] == [("wang", s) for s in ("sparse", "scattered", "overcast")]
    assert all(case.size == (1024, 768) for case in wang)
    modes = {tuple(settings.mode for settings in case.variants) for case in suite.cases}
    assert modes == {("impostor", "auto")} and all(case.auto_vs_faster for case in suite.cases)


def test_a_case_s_frames_follow_its_camera_path_at_its_rate_and_quick_takes_a_thirtieth():
    case = load_suite("lod").chosen(["flythrough"])[0]
    scene = case_scene(case)
    frames = int(scene.camera_path("flythrough").duration * 30) + 1
    assert len(case_views(case, scene)) == frames
    assert len(case_views(case, scene, quick=True)) == max(3, frames // 30)


def test_a_case_at_instants_of_its_path_draws_them_in_turn_and_compares_ways_of_drawing_every_particle():
    suite = load_suite("compositing")
    case = suite.chosen(["flythrough_640"])[0]
    scene = case_scene(case)
    path = scene.camera_path("flythrough")
    assert [round(t - path.keys[0, 0], 9) for t, _ in case_views(case, scene)] == [9.0, 20.0] * 10
    assert (case.reference.mode, case.reference.splat_order, case.reference.compositing) == ("full", "gpu", "raster")
    assert [(v.mode, v.compositing) for v in case.variants] == [("full", "compute")]


def test_a_wind_case_replaces_the_scene_s_wind_and_runs_its_clock_with_the_camera_still():
    suite = load_suite("wind")
    churn = suite.chosen(["churn"])[0]
    scene = case_scene(churn)
    assert [band[1] for band in scene.wind.bands] == [6.0, 18.0] and scene.wind.turbulence_m == 30.0
    views = case_views(churn, scene)
    assert [t for t, _ in views] == [2.0 * frame for frame in range(60)]
    assert {camera for _, camera in views} == {scene.camera}
    field = suite.chosen(["field_still"])[0]
    scene = case_scene(field)
    assert scene.wind is None and scene.cloud_field is not None
    assert [t for t, _ in case_views(field, scene, quick=True)] == [0.0, 2.0, 4.0]


def test_a_harris_case_flies_harris_s_field():
    case = load_suite("lod").chosen(["harris_circle_100"])[0]
    scene = case_scene(case)
    views = case_views(case, scene)
    assert len(scene.clouds) == 100 and not scene.objects
    assert all(len(cloud.particles) == bench_skies.HARRIS_PARTICLES_PER_CLOUD for cloud in scene.clouds)
    assert [camera for _, camera in views] == [camera for _, camera in bench_skies.circle_views(90)]


def _suite(text: str) -> dict:
    import tomllib

    return tomllib.loads(text)


@pytest.mark.parametrize(
    "change, field, problem",
    [
        (("frames = 4", "frames = 4\nspeed = 2"), "cases[0].speed", "unknown key; valid keys: "),
        (('views = "still"', 'views = "hover"'), "cases[0].views", "'hover' is not one of: "),
        (("frames = 4", "frames = 0"), "cases[0].frames", "must be within [1, 100000], got 0"),
        (("frames = 4", "fps = 30"), "cases[0].fps", "only a camera path's views are counted a second"),
        (
            ('views = "still"', 'views = "harris_circle"'),
            "cases[0].views",
            "'harris_circle' flies Harris's field: needs sky.kind = 'harris'",
        ),
        (('views = "still"', 'views = "path"'), "cases[0].camera_path", "views = 'path' needs the name of a camera"),
        (
            ("tolerance_deg = 2.0 }", "tolerance_deg = -1.0 }"),
            "cases[0].variants[1]",
            "tolerance_deg must be within [0, 180]",
        ),
        (('mode = "impostor" }', 'mode = "impostor", colour = 1 }'), "cases[0].variants[0].colour", "unknown key"),
        (('mode = "impostor" }', 'mode = "auto" }'), "cases[0].auto_vs_faster", "exactly one variant in mode 'auto'"),
        (("count = 4 }", "count = 0 }"), "cases[1].sky.count", "must be within [1, 100000], got 0"),
        (('kind = "harris"', 'kind = "wang"'), "cases[1].sky.count", "unknown key; valid keys: kind, scenario"),
        (('name = "tiny_harris"', 'name = "tiny_still"'), "cases[1].name", "'tiny_still' names two cases"),
        (("[defaults]", 'default_cases = ["nowhere"]\n[defaults]'), "default_cases", "no case or group 'nowhere'"),
        (
            ("[defaults]", '[defaults]\nreference = { mode = "impostor" }'),
            "cases[0].reference",
            "the reference draws every particle: mode must be 'full', got 'impostor'",
        ),
        (("frames = 4", "frames = 4\ntimes_s = [1.0]"), "cases[0].times_s", "instants of a camera path"),
        (("frames = 4", "frames = 4\nwind = { bands = [[0, 10]] }"), "cases[0].wind.bands", "3"),
        (("frames = 4", "frames = 4\nseconds_a_frame = -1"), "cases[0].seconds_a_frame", "must be within"),
    ],
)
def test_a_bad_suite_is_refused_in_one_line_naming_its_field(change, field, problem):
    text = TINY_SUITE.replace(*change)
    assert text != TINY_SUITE
    with pytest.raises(SceneError) as caught:
        suite_from_dict(_suite(text), "tiny", "tiny.toml")
    assert caught.value.source == "tiny.toml" and caught.value.field == field
    assert problem in caught.value.problem
    assert "\n" not in str(caught.value)


def _bench(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "bench", *args], capture_output=True, text=True, cwd=cwd
    )


@pytest.mark.parametrize(
    "args, message",
    [
        (["--suite", "nowhere"], "--suite: suite: no suite 'nowhere'; the suites: "),
        (["--suite", "lod", "--cases", "still,nowhere"], "--cases: cases: no case or group 'nowhere' in suite 'lod'"),
        (
            ["--suite", "lod", "--still"],
            "a suite's cases name their own scenes, views, sizes and settings: drop --still",
        ),
        (["--suite", "lod", "--width", "320"], "drop --width/--height"),
        (["--suite", "lod", "--tolerance", "2"], "drop the settings options"),
        (["--cases", "still"], "--cases: cases: only with --suite NAME"),
        ([], "bench: scene: name a scene file, or a suite with --suite NAME"),
    ],
)
def test_a_bad_suite_or_case_name_exits_2_in_one_line(tmp_path, args, message):
    result = _bench(*args, "--json", str(tmp_path / "b.json"))
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.stderr
    assert not (tmp_path / "b.json").exists()


def test_a_bad_suite_file_exits_2_in_one_line(tmp_path):
    suite = tmp_path / "bad.toml"
    suite.write_text(TINY_SUITE.replace("frames = 4", "frames = -4"))
    result = _bench("--suite", str(suite), "--json", str(tmp_path / "b.json"))
    assert result.returncode == 2
    assert result.stderr.strip() == f"cloudview: error: {suite}: cases[0].frames: must be within [1, 100000], got -4"


def test_a_case_flying_a_camera_path_its_scene_lacks_is_refused_before_any_frame(tmp_path):
    suite = tmp_path / "paths.toml"
    suite.write_text(TINY_SUITE.replace('views = "still"', 'views = "path"\ncamera_path = "nowhere"'))
    result = _bench("--suite", str(suite), "--json", str(tmp_path / "b.json"))
    assert result.returncode == 2
    assert result.stderr.strip() == (
        f"cloudview: error: {suite}: cases.tiny_still.camera_path: no camera path 'nowhere' in its scene; it has: "
        "flythrough"
    )


@pytest.mark.gl
def test_a_tiny_suite_runs_end_to_end_and_writes_the_report_it_promises(tmp_path):
    suite, out, plot = tmp_path / "tiny.toml", tmp_path / "tiny.json", tmp_path / "tiny.png"
    suite.write_text(TINY_SUITE)
    result = _bench("--suite", str(suite), "--cases", "tiny_still,tiny", "--json", str(out), "--plot", str(plot))
    if result.returncode != 0 and "EGL" in result.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    assert result.returncode == 0, result.stderr
    report = json.loads(out.read_text())
    assert {"suite", "source", "machine", "date", "quick", "cases", "summary"} <= set(report)
    assert list(report["cases"]) == ["tiny_still", "tiny_harris"]
    still = report["cases"]["tiny_still"]
    assert (still["width"], still["height"], still["warmup"]) == (64, 48, 1)
    assert still["reference"]["settings"]["mode"] == "full"
    assert [len(run["per_frame"]) for run in (still["reference"], *still["runs"])] == [4, 4, 4]
    assert [run["settings"]["tolerance_deg"] for run in still["runs"]] == [0.5, 2.0]
    rows = [row for row in report["summary"] if row["case"] == "tiny_still"]
    assert [row["variant"] for row in rows] == ["reference (full 3D)", "impostor", "auto tolerance_deg=2.0"]
    for row in rows[1:]:
        for key in ("frame_ms", "world_ms", "cloud_ms", "cloud_work_ms"):
            low, ratio, high = (row[f"{key}_vs_reference{end}"] for end in ("_low", "", "_high"))
            assert 0 < low <= ratio <= high
        assert 0 < row["psnr_min"] <= row["psnr_mean"] <= 100
    # auto against the faster of the others, counted from frame 2 of 1 warm-up + 4: the last 3 frames
    frames = [[f["frame_ms"] for f in run["per_frame"][1:]] for run in (still["reference"], *still["runs"])]
    faster = min(sum(frames[0]), sum(frames[1]))
    assert rows[2]["frame_vs_faster"] == pytest.approx(sum(frames[2]) / faster)
    # the clouds' whole work, their plan with it, over full 3D's
    work = [
        [f["plan_ms"] + f["impostor_update_ms"] + f["cloud_ms"] for f in run["per_frame"][1:]]
        for run in (still["reference"], *still["runs"])
    ]
    assert rows[2]["cloud_work_ms_vs_reference"] == pytest.approx(sum(work[2]) / sum(work[0]))
    assert plot.stat().st_size > 0
