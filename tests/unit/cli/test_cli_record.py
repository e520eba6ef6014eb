"""`cloudview record`: a camera path to H.264, PNGs and a CSV; Ctrl-C keeps a playable video; bad input is one line."""

import csv
import signal
import subprocess
import sys
import time

import imageio.v3 as iio
import imageio_ffmpeg
import pytest

from cloudcore.measure.imagecompare import compare
from cloudcore.measure.recording import COLUMNS
from tests.conftest import VALLEY

pytestmark = pytest.mark.gl

SIZE = ["--width", "64", "--height", "48"]
#: two auto runs of the same path: a unit drawn otherwise moves a frame less than auto's frames are from full 3D's
#: (34 dB at worst along the default flythrough); a pass left in another state would break the picture
SAME_FRAME_DB = 30.0


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "record", str(VALLEY), *args], capture_output=True, text=True
    )


def skip_without_egl(result):
    if result.returncode != 0 and "EGL" in result.stderr:
        pytest.skip("no headless OpenGL (EGL) context")


def csv_rows(path):
    with open(path, newline="") as table:
        return list(csv.DictReader(table))


@pytest.fixture(scope="module")
def flythrough(tmp_path_factory):
    """The whole default flythrough (30 s) at 2 fps and 64x48: 61 frames in about 10 s.

    Every frame at 30 fps (901) takes about a minute even at 32x24; the frame
    count and duration arithmetic is the same at 2 fps.
    """
    out = tmp_path_factory.mktemp("record")
    result = run_cli(
        "--camera-path",
        "flythrough",
        "--fps",
        "2",
        *SIZE,
        "--out",
        str(out / "fly.mp4"),
        "--frames-dir",
        str(out / "frames"),
        "--stats",
        str(out / "fly.csv"),
    )
    skip_without_egl(result)
    assert result.returncode == 0, result.stderr
    return out


def test_the_video_has_every_frame_of_the_path_and_its_duration(flythrough):
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(flythrough / "fly.mp4"))
    assert frames == 61  # t = 0, 0.5, ... 30 s
    assert seconds == pytest.approx(30.5)  # 61 frames of 0.5 s each


def test_one_csv_row_and_one_png_per_frame(flythrough):
    rows = csv_rows(flythrough / "fly.csv")
    assert len(rows) == 61 and tuple(rows[0]) == COLUMNS
    assert [float(row["time_s"]) for row in rows] == [i / 2 for i in range(61)]
    for row in rows:
        parts = float(row["cloud_ms"]) + float(row["impostor_update_ms"]) + float(row["other_ms"])
        assert parts == pytest.approx(float(row["frame_ms"]), abs=0.01)
        assert float(row["overdraw_mean"]) >= 0 and int(row["texture_bytes"]) > 0
    assert int(rows[0]["impostors_regenerated"]) > 0  # auto mode builds its impostors on the first frame
    pngs = sorted((flythrough / "frames").iterdir())
    assert [p.name for p in pngs[:2]] == ["frame_00000.png", "frame_00001.png"] and len(pngs) == 61
    assert iio.imread(pngs[-1]).shape == (48, 64, 3)


def test_the_same_inputs_give_the_same_frames(flythrough, tmp_path):
    """Measuring overdraw (done in the first run, not here) leaves the frames alone too.

    Auto mode chooses by the pass times it measures, so on a loaded machine a unit may be drawn otherwise (an
    impostor where the first run drew its particles): the frames are the same within `SAME_FRAME_DB`."""
    result = run_cli(
        "--camera-path",
        "flythrough",
        "--fps",
        "2",
        *SIZE,
        "--frames",
        "4",
        "--frames-dir",
        str(tmp_path / "f"),
        "--stats",
        str(tmp_path / "s.csv"),
        "--no-overdraw",
    )
    assert result.returncode == 0, result.stderr
    assert [row["overdraw_mean"] for row in csv_rows(tmp_path / "s.csv")] == [""] * 4
    again = sorted((tmp_path / "f").iterdir())
    assert len(again) == 4
    for png in again:
        psnr = compare(iio.imread(png), iio.imread(flythrough / "frames" / png.name)).psnr_db
        assert psnr >= SAME_FRAME_DB, f"{png.name}: {psnr:.1f} dB from the first run's"


def test_ctrl_c_keeps_a_playable_video_of_the_frames_so_far(tmp_path):
    video, table = tmp_path / "cut.mp4", tmp_path / "cut.csv"
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "cloudcore.cli",
            "record",
            str(VALLEY),
            "--camera-path",
            "flythrough",
            *SIZE,
            "--out",
            str(video),
            "--stats",
            str(table),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while process.poll() is None and time.monotonic() < deadline:
        if table.exists() and len(table.read_text().splitlines()) > 3:  # the header and three frames
            break
        time.sleep(0.02)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    skip_without_egl(subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr))
    assert process.returncode == 130, stderr
    rows = csv_rows(table)
    assert 3 <= len(rows) < 901
    assert f"interrupted: wrote {len(rows)} frames" in stderr.strip().splitlines()[-1]
    assert imageio_ffmpeg.count_frames_and_secs(str(video))[0] == len(rows)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--camera-path", "flythrough"], "give --out FILE.mp4, --frames-dir DIR, or both"),
        (["--camera-path", "nowhere", "--frames-dir", "{tmp}/f"], "no camera path named 'nowhere'"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--width", "63"], "needs an even width and height"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--fps", "0"], "--fps"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--fps", "nan"], "--fps"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--fps", "inf"], "--fps"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--frames", "0"], "--frames"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--clock-rate", "0"], "--clock-rate"),
        (["--camera-path", "flythrough", "--out", "{tmp}/x.mp4", "--clock-rate", "inf"], "--clock-rate"),
        (["--camera-path", "flythrough", "--out", "{tmp}/file/x.mp4"], "{tmp}/file/x.mp4: output:"),
        (["--camera-path", "flythrough", "--frames-dir", "{tmp}/file"], "{tmp}/file: output:"),
        (
            ["--camera-path", "flythrough", "--frames-dir", "{tmp}/f", "--stats", "{tmp}/file/s.csv"],
            "{tmp}/file/s.csv: output:",
        ),
    ],
)
def test_bad_record_arguments_exit_2_in_one_line(tmp_path, args, message):
    (tmp_path / "file").write_text("a file where a folder is needed")
    result = run_cli(*(arg.format(tmp=tmp_path) for arg in args))
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message.format(tmp=tmp_path) in lines[0], result.stderr
    assert not (tmp_path / "x.mp4").exists()


def test_a_missing_scene_is_one_line(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "cloudcore.cli",
            "record",
            str(tmp_path / "none.toml"),
            "--camera-path",
            "flythrough",
            "--out",
            str(tmp_path / "x.mp4"),
        ],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert "none.toml" in result.stderr
