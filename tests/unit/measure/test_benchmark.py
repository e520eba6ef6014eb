"""`cloudview bench` and its engine: the report contract, the Pareto front, errors against the reference."""

import json
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest

from cloudcore.lod.plan.plan_stats import PlanStats
from cloudcore.measure import benchmark
from cloudcore.measure.benchmark import bench_path, pareto_front, ratio_interval, turns
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.scenes.files import load_scene
from cloudcore.stats.frame_stats import FrameStats
from tests.conftest import VALLEY

CONTRACT_RUN_KEYS = {
    "settings",
    "frame_ms_mean",
    "frame_ms_p95",
    "speedup_vs_full",
    "psnr_mean",
    "psnr_min",
    "mad_mean",
    "regenerations",
    "texture_bytes_max",
}


def test_pareto_front_keeps_the_points_nothing_beats():
    seconds = [10.0, 20.0, 15.0, 30.0, 15.0]
    errors = [5.0, 1.0, 6.0, 0.5, 2.0]
    assert pareto_front(seconds, errors) == [0, 1, 3, 4]


def test_a_ratio_of_proportional_frames_is_exact_and_its_interval_has_no_width():
    frames = np.random.default_rng(3).uniform(20.0, 40.0, size=60)
    assert ratio_interval(1.05 * frames, [frames]) == pytest.approx((1.05, 1.05, 1.05))


def test_a_ratio_is_against_the_lowest_mean_of_its_denominators():
    frames = np.full(30, 10.0)
    ratio, low, high = ratio_interval(frames, [2.0 * frames, 0.8 * frames, 4.0 * frames])
    assert (ratio, low, high) == pytest.approx((1.25, 1.25, 1.25))


def test_a_ratio_interval_pairs_the_frames_so_the_machines_slow_phases_cancel():
    # slow phases of several frames, shared by both runs, each run with its own small noise: the ratio is 1.1
    rng = np.random.default_rng(7)
    phases = np.repeat(rng.uniform(15.0, 35.0, size=12), 10)
    auto, faster = 1.1 * phases + rng.normal(0.0, 0.5, 120), phases + rng.normal(0.0, 0.5, 120)
    ratio, low, high = ratio_interval(auto, [faster])
    assert low < 1.1 < high and high - low < 0.02, (ratio, low, high)
    # the same frames taken apart (the faster run's reversed) no longer share the phases: far wider
    _, apart_low, apart_high = ratio_interval(auto, [faster[::-1]])
    assert apart_high - apart_low > 5.0 * (high - low)


def test_a_ratio_interval_wants_runs_of_the_same_frames():
    with pytest.raises(ValueError):
        ratio_interval([1.0, 2.0, 3.0], [[1.0, 2.0]])
    with pytest.raises(ValueError):
        ratio_interval([1.0, 2.0], [])


class FakeRenderer:
    """Full 3D is grey 100; every other mode adds `offset` levels: the bench must see exactly that error.
    Every render is logged in `calls` as (renderer's name, camera position) in the order made."""

    def __init__(self, offset, name="", calls=None):
        self.offset, self.name, self.calls = offset, name, calls if calls is not None else []

    def render(self, scene, camera=None, settings=None, time_s=0.0):
        self.calls.append((self.name, tuple(camera.position)))
        level = 100 if settings == FULL_3D else 100 + self.offset
        stats = FrameStats(
            PlanStats(impostors_regenerated=1),
            frame_ms=40.0 if settings == FULL_3D else 10.0,
            world_ms=5.0,
            cloud_ms=30.0,
            texture_bytes=1024,
            world_gpu_ms=2.0,
            impostor_update_gpu_ms=0.0 if settings == FULL_3D else 3.0,
            cloud_gpu_ms=7.0,
            splat_order="cpu" if settings == FULL_3D else "gpu",
        )
        return np.full((4, 4, 3), level, dtype=np.uint8), stats


def test_bench_path_reports_the_error_and_speedup_it_measured():
    scene = load_scene(VALLEY)
    report = bench_path([FakeRenderer(offset=5) for _ in range(2)], scene, "flythrough", 3, [RenderSettings()], (4, 4))
    (run,) = report["runs"]
    assert CONTRACT_RUN_KEYS <= set(run)
    assert run["psnr_mean"] == pytest.approx(10 * np.log10(255**2 / 25))
    assert run["mad_mean"] == 5.0 and run["speedup_vs_full"] == 4.0 and run["regenerations"] == 3
    assert report["reference"]["mode"] == "full" and report["frames"] == 3
    assert run["gpu_ms_by_pass"] == {"clouds": 7.0, "impostor_updates": 3.0, "world": 2.0}
    assert run["gpu_ms_mean"] == 12.0 and report["reference"]["gpu_ms_by_pass"]["impostor_updates"] == 0.0
    # the way each frame sorted, frame by frame and counted: what a GPU's "auto" trial kept
    assert [row["splat_order"] for row in run["per_frame"]] == ["gpu"] * 3 and run["splat_order_frames"] == {"gpu": 3}
    assert report["reference"]["splat_order_frames"] == {"cpu": 3}
    twins = [FakeRenderer(offset=0) for _ in range(2)]
    identical = bench_path(twins, scene, "flythrough", 2, [RenderSettings()], (4, 4))
    assert identical["runs"][0]["psnr_min"] == 100.0  # identical frames: the cap, JSON has no infinity


def test_bench_path_renders_frame_by_frame_in_turn_in_the_balanced_order():
    """Side by side: every renderer renders a frame before any renders the next, so a slower or faster spell of
    the machine falls on all runs alike; in the order of `turns`."""
    scene, calls = load_scene(VALLEY), []
    renderers = [FakeRenderer(offset=1, name=name, calls=calls) for name in ("full", "a", "b")]
    bench_path(renderers, scene, "flythrough", 4, [RenderSettings(), RenderSettings(mode="impostor")], (4, 4))
    measured = calls[3:]  # after one unmeasured frame each: shading precompute, shader compiles
    names = ("full", "a", "b")
    assert [name for name, _ in measured] == [names[run] for frame in turns(3, 4) for run in frame]
    positions = [position for _, position in measured]
    assert all(len(set(positions[i : i + 3])) == 1 for i in range(0, 12, 3)) and positions[0] != positions[3]


@pytest.mark.parametrize("runs", [3, 4, 5])
def test_each_run_follows_each_other_equally_often_never_itself_and_takes_each_place_alike(runs):
    order = turns(runs, 60 * runs)
    assert all(sorted(frame) == list(range(runs)) for frame in order)
    sequence = [run for frame in order for run in frame]
    follows = Counter(zip(sequence, sequence[1:]))
    assert not any(follows[run, run] for run in range(runs))
    others = [follows[a, b] for a in range(runs) for b in range(runs) if a != b]
    assert max(others) - min(others) <= 2
    places = Counter((run, place) for frame in order for place, run in enumerate(frame))
    assert max(places.values()) - min(places.values()) <= 0.1 * len(order) / runs + 2


def test_a_benchmark_freezes_what_is_set_up_after_the_warm_up_and_before_the_measured_frames(monkeypatch):
    """A full collection is a 70 ms stall (`cloudcore.runtime.collector`): it must not fall in a measured frame."""
    scene, calls = load_scene(VALLEY), []
    monkeypatch.setattr(benchmark, "freeze_what_is_set_up", lambda: calls.append(("frozen", None)))
    renderers = [FakeRenderer(offset=1, name=name, calls=calls) for name in ("full", "a")]
    bench_path(renderers, scene, "flythrough", 2, [RenderSettings()], (4, 4), warmup=3, freeze=True)
    assert [name for name, _ in calls].index("frozen") == 2 + 2 * 3  # first frames, warm-up, then frozen
    calls.clear()
    bench_path(renderers, scene, "flythrough", 2, [RenderSettings()], (4, 4), warmup=3)
    assert ("frozen", None) not in calls  # a test's process is not frozen


def test_bench_path_wants_a_renderer_per_run():
    with pytest.raises(ValueError, match="2 renderers for the reference and 2 settings"):
        bench_path([FakeRenderer(0)] * 2, load_scene(VALLEY), "flythrough", 2, [RenderSettings()] * 2, (4, 4))


def test_bench_cli_writes_the_contract(tmp_path):
    out = tmp_path / "bench.json"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "cloudcore.cli",
            "bench",
            str(VALLEY),
            "--camera-path",
            "flythrough",
            "--frames",
            "2",
            "--width",
            "48",
            "--height",
            "32",
            "--sweep",
            "tolerance=0.15,2",
            "--sweep",
            "regeneration_budget=0,1",
            "--without-terrain",
            "--json",
            str(out),
            "--plot",
            str(tmp_path / "plot.png"),
            "--no-shading",
        ],
        capture_output=True,
        text=True,
    )
    if result.returncode != 0 and "EGL" in result.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    assert result.returncode == 0, result.stderr
    report = json.loads(out.read_text())
    assert {"scene", "path", "width", "height", "frames", "reference", "runs", "shading"} <= set(report)
    assert [(r["settings"]["tolerance_deg"], r["settings"]["regeneration_budget"]) for r in report["runs"]] == [
        (0.15, 0),
        (0.15, 1),
        (2.0, 0),
        (2.0, 1),
    ]
    assert all(CONTRACT_RUN_KEYS <= set(r) and len(r["per_frame"]) == 2 for r in report["runs"])
    assert report["without_terrain"] is True
    assert (tmp_path / "plot.png").stat().st_size > 0


@pytest.mark.parametrize(
    "args, message",
    [
        (["--camera-path", "nowhere"], "no camera path named 'nowhere'"),
        (["--camera-path", "flythrough", "--sweep", "colour=1,2"], "--sweep"),
        (["--camera-path", "flythrough", "--sweep", "impostor_max_size=300"], "power of two"),
        (["--camera-path", "flythrough", "--regeneration-budget", "-1"], "regeneration_budget"),
    ],
)
def test_bad_bench_arguments_exit_2_in_one_line(tmp_path, args, message):
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "bench", str(VALLEY), "--json", str(tmp_path / "b.json"), *args],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.stderr
