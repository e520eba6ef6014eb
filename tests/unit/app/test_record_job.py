"""The editor's background recording: `cloudview record` in a subprocess, polled without waiting."""

import time

import imageio_ffmpeg
import numpy as np
import pytest

from app.record_job import RecordJob, standalone
from cloudcore.model.scene import CameraPath, Cloud, Scene, SceneObject, Terrain


def finished(job: RecordJob, timeout_s: float = 120.0) -> int:
    deadline = time.monotonic() + timeout_s
    while (status := job.poll()) is None:
        assert time.monotonic() < deadline, f"still recording after {timeout_s} s: {job.progress}"
        time.sleep(0.1)
    return status


def test_a_copy_for_recording_names_its_meshes_absolutely_and_keeps_its_particles_with_it(tmp_path):
    scene = Scene(
        clouds=(Cloud("big", np.ones((3, 4)), particles_file="other.particles/big.npy"),),
        terrain=Terrain(kind="mesh", mesh="ground.obj"),
        objects=(SceneObject("tower", mesh="meshes/tower.obj"), SceneObject("box", primitive="box")),
    )
    copy = standalone(scene, tmp_path)
    assert copy.terrain.mesh == str(tmp_path.resolve() / "ground.obj")
    assert [o.mesh for o in copy.objects] == [str(tmp_path.resolve() / "meshes" / "tower.obj"), None]
    assert copy.clouds[0].particles_file is None and np.array_equal(copy.clouds[0].particles, np.ones((3, 4)))


def test_a_recording_runs_in_the_background_and_reports_how_it_ended(small_scene, tmp_path):
    out = tmp_path / "orbit.mp4"
    job = RecordJob(small_scene, tmp_path, "orbit", out, 32, 24, fps=0.4)  # a 5 s path: 3 frames
    assert job.poll() is None  # started, not waited for
    status = finished(job)
    if status != 0 and "EGL" in job.progress:
        pytest.skip("no headless OpenGL (EGL) context")
    assert status == 0, job.progress
    assert job.progress.startswith("wrote 3 frames")
    assert imageio_ffmpeg.count_frames_and_secs(str(out))[0] == 3
    failing = RecordJob(small_scene, tmp_path, "no such path", tmp_path / "x.mp4", 32, 24, fps=1.0)
    assert finished(failing) == 2
    assert "cloudview: error" in failing.progress and "no camera path named 'no such path'" in failing.progress


def test_a_stopped_recording_ends_like_ctrl_c(small_scene, tmp_path):
    long_path = CameraPath("long", [[0, 0, 500, 1500, 0, 800, 0], [600, 1500, 600, 0, 0, 800, 0]])
    job = RecordJob(
        Scene(clouds=small_scene.clouds, camera_paths=(long_path,)),
        tmp_path,
        "long",
        tmp_path / "long.mp4",
        32,
        24,
        fps=30.0,
    )
    deadline = time.monotonic() + 60.0
    while "frame" not in job.progress and time.monotonic() < deadline:  # tqdm's bar: frames are being drawn
        time.sleep(0.1)
    job.stop()
    status = finished(job)
    if status not in (0, 130) and "EGL" in job.progress:
        pytest.skip("no headless OpenGL (EGL) context")
    assert status == 130, job.progress
    assert "interrupted" in job.progress
