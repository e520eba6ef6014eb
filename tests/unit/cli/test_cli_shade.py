import subprocess
import sys

from cloudcore.scenes.files import save_scene


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "cloudcore.cli", *args], capture_output=True, text=True)


def test_shade_prints_a_line_per_cloud_with_statistics(tmp_path, small_scene):
    save_scene(small_scene, tmp_path / "s.toml")
    result = run_cli("shade", str(tmp_path / "s.toml"))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    small = next(line for line in lines if line.startswith("small"))
    large = next(line for line in lines if line.startswith("large"))
    assert small.split()[1] == "12" and large.split()[1] == "200"
    # two explicit lights: two min / mean / max triples, all within [0, 1]
    values = [float(x) for x in large.split()[3:] if x != "/"]
    assert len(values) == 6 and all(0 <= v <= 1 for v in values)
    assert "2 active light(s)" in lines[0]


def test_shade_raster_method(tmp_path, small_scene):
    save_scene(small_scene, tmp_path / "s.toml")
    assert run_cli("shade", str(tmp_path / "s.toml"), "--method", "raster").returncode == 0


def test_bad_arguments_exit_2_in_one_line():
    result = run_cli("shade", "x.toml", "--method", "magic")
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1
    result = run_cli("shade", "/nonexistent/x.toml")
    assert result.returncode == 2
    assert result.stderr.strip() == "cloudview: error: /nonexistent/x.toml: (file): no such file"
