"""`--workers N` of `cloudview record`, `truth`, `check` and `bench`: the same output as the command run in one
process (a bench's settings each measured beside its own worker's reference), a worker killed on purpose has its
piece run again, one killed on every try fails the job in one line."""

import importlib.util
import json
import os
import subprocess
import sys
import types

import pytest

from cloudcore.cli import main
from cloudcore.cli.workers import KILL_PIECE_ENV, RETRIES, _use_the_task_s_gpu, task_gpus
from cloudcore.gl.context import egl_device_of_cuda
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Camera, Cloud, Light, Lighting, Scene, Shading
from cloudcore.resources import resource_path
from cloudcore.scenes.files import save_scene
from tests.conftest import VALLEY

EXAMPLE = resource_path("scenes", "aircraft_in_cloud.toml")


def cloudview(*args, kill: str | None = None):
    env = dict(os.environ)
    env.pop(KILL_PIECE_ENV, None)
    if kill is not None:
        env[KILL_PIECE_ENV] = kill
    return subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", *map(str, args)], capture_output=True, text=True, env=env
    )


def files_of(folder):
    return {path.relative_to(folder): path.read_bytes() for path in sorted(folder.rglob("*")) if path.is_file()}


@pytest.mark.parametrize("command", ["record", "truth", "check", "bench"])
@pytest.mark.parametrize("count", ["0", "-2"])
def test_no_workers_is_refused_in_one_line(command, count, capsys):
    with pytest.raises(SystemExit) as stopped:
        main([command, str(VALLEY), "--workers", count])
    assert stopped.value.code == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and f"argument --workers: invalid worker_count value: '{count}'" in error


@pytest.mark.gl
def test_a_recording_on_two_workers_has_the_frames_of_one_process_even_when_a_worker_dies(tmp_path):
    """Full 3D, whose frames depend on nothing but their time; 10 frames: runs of 8 and 2, the second run's
    worker killed on its first try."""
    common = ["record", VALLEY, "--camera-path", "flythrough", "--fps", "2", "--frames", "10"]
    common += ["--width", "32", "--height", "24", "--mode", "full"]
    alone = cloudview(*common, "--out", tmp_path / "one.mp4", "--frames-dir", tmp_path / "one")
    if alone.returncode != 0 and "EGL" in alone.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    assert alone.returncode == 0, alone.stderr
    spread = cloudview(
        *common, "--out", tmp_path / "two.mp4", "--frames-dir", tmp_path / "two", "--workers", "2", kill="1"
    )
    assert spread.returncode == 0, spread.stderr
    assert f"cloudview record: frames 8-9: its worker died; running it again (try 2 of {RETRIES + 1})" in (
        spread.stderr
    )
    assert len(files_of(tmp_path / "one")) == 10
    assert files_of(tmp_path / "two") == files_of(tmp_path / "one")
    assert (tmp_path / "two.mp4").read_bytes() == (tmp_path / "one.mp4").read_bytes()


@pytest.mark.gl
def test_a_check_on_two_workers_gives_the_verdicts_and_images_of_one_process_even_when_a_worker_dies(tmp_path):
    common = ["check", EXAMPLE, "--goldens", tmp_path / "goldens", "--size", "32x24"]
    made = cloudview(*common, "--update")
    if made.returncode != 0 and "EGL" in made.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    assert made.returncode == 0, made.stderr
    alone = cloudview(*common, "--report", tmp_path / "one")
    spread = cloudview(*common, "--report", tmp_path / "two", "--workers", "2", kill="2")
    assert alone.returncode == spread.returncode == 0, spread.stderr
    assert "4 views: 4 passed" in alone.stdout
    assert spread.stdout.replace(str(tmp_path / "two"), "REPORT") == alone.stdout.replace(
        str(tmp_path / "one"), "REPORT"
    )
    assert "view aircraft_in_cloud/aircraft_inside: its worker died; running it again" in spread.stderr
    assert files_of(tmp_path / "two") == files_of(tmp_path / "one")


@pytest.mark.gl
def test_a_sweep_on_two_workers_measures_each_setting_beside_its_own_reference_even_when_a_worker_dies(tmp_path):
    """Three settings dealt to two workers (the first and third to one): the runs in the sweep's order, each
    with its group's reference, its speed-up against that reference; the second group's worker killed once."""
    common = ["bench", VALLEY, "--still", "--frames", "2", "--width", "32", "--height", "24", "--no-shading"]
    common += ["--mode", "impostor", "--sweep", "tolerance=0.15,1,2"]
    spread = cloudview(*common, "--json", tmp_path / "two.json", "--workers", "2", kill="1")
    if spread.returncode != 0 and "EGL" in spread.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    assert spread.returncode == 0, spread.stderr
    assert "cloudview bench: settings group 1: its worker died; running it again" in spread.stderr
    report = json.loads((tmp_path / "two.json").read_text())
    assert [run["settings"]["tolerance_deg"] for run in report["runs"]] == [0.15, 1.0, 2.0]
    assert [run["reference_group"] for run in report["runs"]] == [0, 1, 0]
    assert (
        len(report["references"]) == 2
        and report["reference"]["frame_ms_mean"] == report["references"][0]["frame_ms_mean"]
    )
    for run in report["runs"]:
        reference = report["references"][run["reference_group"]]
        assert run["speedup_vs_full"] == pytest.approx(reference["frame_ms_mean"] / run["frame_ms_mean"])
        assert len(run["per_frame"]) == 2
    assert {"scene", "path", "width", "height", "frames", "shading"} <= set(report)


@pytest.fixture
def truth_scene(tmp_path):
    pytest.importorskip("mitsuba")
    centre = (0.0, 1000.0, 0.0)
    save_scene(
        Scene(
            camera=Camera((0.0, 1000.0, 300.0), centre, 40.0),
            lighting=Lighting(time_of_day=None, lights=(Light((0.3, 0.9, 0.3), (1.0, 1.0, 1.0), 1.0),)),
            shading=Shading(albedo=0.9, optical_depth=4.0),
            clouds=(Cloud("one", [[*centre, 50.0]]),),
        ),
        tmp_path / "s.toml",
    )
    return tmp_path / "s.toml"


def test_a_truth_is_the_same_picture_on_any_number_of_workers_even_when_a_worker_dies(truth_scene, tmp_path):
    """40 spp: passes of 16, 16 and 8 samples, each seeded apart."""

    def truth(name, *workers, kill=None):
        result = cloudview(
            "truth",
            truth_scene,
            "--out",
            tmp_path / name,
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "40",
            *workers,
            kill=kill,
        )
        assert result.returncode == 0, result.stderr
        return (tmp_path / name).read_bytes(), result.stderr

    alone, _ = truth("alone.png")
    assert truth("one.png", "--workers", "1")[0] == alone
    spread, said = truth("two.png", "--workers", "2", kill="1")
    assert spread == alone
    assert "cloudview truth: pass 1 (seed 0): its worker died; running it again (try 2 of 3)" in said
    other_seed = cloudview(
        "truth",
        truth_scene,
        "--out",
        tmp_path / "seed1.png",
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "40",
        "--seed",
        "1",
    )
    assert (tmp_path / "seed1.png").read_bytes() != alone, other_seed.stderr


def test_a_piece_whose_worker_dies_on_every_try_fails_the_job_in_one_line(truth_scene, tmp_path):
    result = cloudview(
        *("truth", truth_scene, "--out", tmp_path / "t.png", "--width", "8", "--height", "6", "--spp", "32"),
        *("--workers", "2"),
        kill=f"1:{RETRIES + 1}",
    )
    assert result.returncode == 2
    last = result.stderr.strip().splitlines()[-1]
    assert last == (
        f"cloudview: error: cloudview truth: pass 1 (seed 0): its worker died on each of {RETRIES + 1} tries: "
        "the job is given up"
    )
    assert "Traceback" not in result.stderr and not (tmp_path / "t.png").exists()


def test_without_ray_a_cluster_is_refused_with_the_extra_to_install(monkeypatch, capsys):
    found = importlib.util.find_spec
    monkeypatch.setattr("importlib.util.find_spec", lambda name, *rest: None if name == "ray" else found(name, *rest))
    with pytest.raises(SystemExit) as stopped:
        main(["check", str(EXAMPLE), "--goldens", "g", "--cluster", "auto"])
    assert stopped.value.code == 2
    assert capsys.readouterr().err == (
        "cloudview check: error: argument --cluster: needs Ray, which is not installed: "
        "pip install 'cloudview[cluster]' (see --help)\n"
    )


def test_a_cluster_that_does_not_answer_is_refused_at_once_in_one_line(monkeypatch, capsys, tmp_path):
    """Ray itself waits minutes for a head that is not there; nothing listens on port 1 here."""
    found = importlib.util.find_spec
    monkeypatch.setattr("importlib.util.find_spec", lambda name, *rest: name == "ray" or found(name, *rest))
    assert main(["check", str(EXAMPLE), "--goldens", str(tmp_path), "--cluster", "127.0.0.1:1"]) == 2
    assert (
        capsys.readouterr().err == "cloudview: error: --cluster: 127.0.0.1:1: cannot be reached: Connection refused\n"
    )


def test_a_task_asks_for_a_gpu_where_the_cluster_has_them_and_a_job_asking_too_many_is_refused():
    assert task_gpus({"CPU": 16.0}, None, "auto") == (0.0, 16)  # no GPUs: a task a CPU
    assert task_gpus({"CPU": 16.0, "GPU": 4.0}, None, "auto") == (1.0, 4)  # a GPU a task, four at a time
    assert task_gpus({"CPU": 16.0, "GPU": 2.0}, 0.25, "auto") == (0.25, 8)  # four tasks share each GPU
    assert task_gpus({"CPU": 16.0, "GPU": 2.0}, 0.0, "auto") == (0.0, 16)  # the GPUs left to other jobs
    with pytest.raises(SceneError) as refused:
        task_gpus({"CPU": 8.0}, 1.0, "head:6379")  # Ray would wait forever for a GPU
    assert str(refused.value) == "--gpus-per-task: 1: the cluster at head:6379 has 0 GPUs"


def test_gpus_without_a_cluster_are_refused_in_one_line(capsys, tmp_path):
    assert main(["check", str(EXAMPLE), "--goldens", str(tmp_path), "--workers", "2", "--gpus-per-task", "1"]) == 2
    assert capsys.readouterr().err == "cloudview: error: --gpus-per-task: 1: asks Ray for GPUs: it needs --cluster\n"


def test_a_ray_task_draws_on_the_gpu_ray_gave_it(monkeypatch):
    """Ray names the task's GPU as CUDA does; its context is made on the EGL device that is that CUDA device."""
    monkeypatch.setitem(sys.modules, "ray", types.SimpleNamespace(get_gpu_ids=lambda: [3]))
    monkeypatch.setattr("cloudcore.gl.context.egl_device_of_cuda", lambda cuda: {3: 1}.get(cuda))
    # set, then removed: monkeypatch then takes the variable the task sets out again afterwards (a variable it only
    # deleted, absent, it would leave set, and every later subprocess's context on EGL device 1)
    monkeypatch.setenv("EGL_DEVICE_ID", "0")
    monkeypatch.delenv("EGL_DEVICE_ID")
    _use_the_task_s_gpu()
    assert os.environ["EGL_DEVICE_ID"] == "1"


@pytest.mark.gl
def test_a_device_that_does_not_say_it_is_a_cuda_device_is_none_of_them():
    """Mesa's EGL devices (llvmpipe here) have no CUDA device: the default device stays."""
    assert egl_device_of_cuda(0) is None


def test_a_truth_on_a_local_ray_is_the_picture_of_one_process_even_when_a_task_s_worker_dies(truth_scene, tmp_path):
    """`--cluster local` starts a Ray on this machine (as many CPUs as it has: 2 here)."""
    pytest.importorskip("ray")
    size = ["--width", "32", "--height", "24", "--spp", "40"]
    alone = cloudview("truth", truth_scene, "--out", tmp_path / "alone.png", *size)
    on_ray = cloudview("truth", truth_scene, "--out", tmp_path / "ray.png", *size, "--cluster", "local", kill="2")
    assert alone.returncode == on_ray.returncode == 0, on_ray.stderr
    assert "cloudview truth: pass 2 (seed 0): its worker died; running it again (try 2 of 3)" in on_ray.stderr
    assert (tmp_path / "ray.png").read_bytes() == (tmp_path / "alone.png").read_bytes()
