"""`cloudview render`: a PNG and stats from the command line; bad arguments are one line, status 2."""

import json
import subprocess
import sys

import imageio.v3 as iio
import numpy as np
import pytest

from tests.conftest import VALLEY

pytestmark = pytest.mark.gl


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "cloudcore.cli", *args], capture_output=True, text=True)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    out = tmp_path_factory.mktemp("render")
    result = run_cli(
        "render",
        str(VALLEY),
        "--out",
        str(out / "v.png"),
        "--width",
        "96",
        "--height",
        "64",
        "--camera-path",
        "flythrough",
        "--path-time",
        "4",
        "--time-of-day",
        "17",
        "--stats",
        str(out / "v.json"),
        "--overdraw",
        str(out / "heat.png"),
    )
    if result.returncode != 0 and "EGL" in result.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    return result, out


def test_render_writes_the_png_and_the_stats(rendered):
    result, out = rendered
    assert result.returncode == 0, result.stderr
    image = iio.imread(out / "v.png")
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8
    stats = json.loads((out / "v.json").read_text())
    assert {
        "frame_ms",
        "world_ms",
        "cloud_ms",
        "particles_drawn",
        "clouds_drawn",
        "clouds_culled",
        "overdraw_mean",
        "overdraw_max",
        "overdraw_analytic",
        "block_overdraw_mean",
        "blocks",
    } <= set(stats)
    assert stats["overdraw_max"] >= stats["overdraw_mean"] > 0
    assert iio.imread(out / "heat.png").shape == (64, 96, 3)
    assert stats["clouds_drawn"] + stats["clouds_culled"] == 34
    assert str(out / "v.png") in result.stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (["--width", "0"], "--width"),
        (["--time-of-day", "25"], "--time-of-day: time_of_day: must be within [0, 24]"),
        (["--camera-path", "nowhere"], "no camera path named 'nowhere'"),
        (["--mode", "sideways"], "--mode"),
        (["--cloud-resolution", "0.01"], "cloud_resolution_scale must be 'auto' or within [0.125, 1], got 0.01"),
        (["--cloud-resolution", "nan"], "cloud_resolution_scale must be 'auto' or within [0.125, 1], got nan"),
        (["--cloud-resolution", "often"], "--cloud-resolution"),
        (["--particle-shading", "per_voxel"], "--particle-shading"),
        (["--detail-noise", "3"], "detail_noise must be within [0, 1], got 3.0"),
        (["--detail-noise-scale", "0"], "detail_noise_scale_m must be within (0, 10000] metres, got 0.0"),
    ],
)
def test_bad_render_arguments_exit_2_in_one_line(tmp_path, args, message):
    result = run_cli("render", str(VALLEY), "--out", str(tmp_path / "x.png"), *args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.stderr
    assert not (tmp_path / "x.png").exists()


def test_render_imports_no_gui():
    code = (
        "import sys; from cloudcore.cli import main; import cloudcore.cli.render; "
        "assert not [m for m in sys.modules if m.startswith(('imgui_bundle', 'app'))]"
    )
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_render_without_a_scene_renders_the_built_in_default_from_any_directory(tmp_path):
    """The default scene ships in the package: no checkout path is needed (issue 18)."""
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "cloudcore.cli",
            "render",
            "--out",
            "d.png",
            "--width",
            "48",
            "--height",
            "32",
            "--stats",
            "d.json",
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    if result.returncode != 0 and "EGL" in result.stderr:
        pytest.skip("no headless OpenGL (EGL) context")
    assert result.returncode == 0, result.stderr
    assert iio.imread(tmp_path / "d.png").shape == (32, 48, 3)
    # the default view of the valley (README): 32 of its 34 clouds drawn
    assert json.loads((tmp_path / "d.json").read_text())["clouds_drawn"] == 32
