"""The pytest plugin (`cloudview_check`), used by a user's test in a temporary project outside tests/: goldens
beside the test module, --cloudview-update-goldens, a failure's one line and images, --cloudview-report."""

import dataclasses

import imageio.v3 as iio
import pytest

# The user's pytest runs in this process (pytester), which forgets the modules that run imported; numpy's
# extension modules cannot load twice, so what the plugin renders with is imported here first.
import cloudcore.gl.views  # noqa: F401
from cloudcore.scenes.files import load_scene, save_scene
from tests.unit.cli.test_cli_check import sky_scene

pytest_plugins = ["pytester"]
pytestmark = pytest.mark.gl

USER_TEST = """
def test_sky(cloudview_check):
    cloudview_check("scenes/sky.toml", size=(96, 72))


def test_dusk(cloudview_check):
    result = cloudview_check("scenes/sky.toml", "dusk", size=(96, 72), max_diff=20)
    assert result.tolerance.max_diff == 20
"""


@pytest.fixture
def user_project(pytester):
    """A project of the user's: a scene with a view, and a test of two views (the plugin comes by entry point)."""
    save_scene(sky_scene(), pytester.path / "scenes" / "sky.toml")
    pytester.makepyfile(test_clouds=USER_TEST)
    return pytester


def test_the_plugin_writes_goldens_then_passes_then_catches_a_change(user_project):
    project = user_project.path
    first = user_project.runpytest()
    first.assert_outcomes(failed=2)
    first.stdout.fnmatch_lines(
        ["*sky/default: no golden: *does not exist; to write it: pytest --cloudview-update-goldens*"]
    )

    user_project.runpytest("--cloudview-update-goldens").assert_outcomes(skipped=2)
    goldens = project / "cloudview_goldens" / "sky"
    assert sorted(path.name for path in goldens.iterdir()) == ["default.png", "dusk.png"]
    assert iio.imread(goldens / "default.png").shape == (72, 96, 3)
    # updating again changes nothing: the tests pass and the goldens stay as they were
    modified = (goldens / "default.png").stat().st_mtime_ns
    user_project.runpytest("--cloudview-update-goldens").assert_outcomes(passed=2)
    assert (goldens / "default.png").stat().st_mtime_ns == modified
    user_project.runpytest().assert_outcomes(passed=2)

    scene_file = project / "scenes" / "sky.toml"
    scene = load_scene(scene_file)
    save_scene(dataclasses.replace(scene, lighting=dataclasses.replace(scene.lighting, time_of_day=9.0)), scene_file)
    report = project / "report"
    changed = user_project.runpytest("--cloudview-report", str(report))
    changed.assert_outcomes(failed=1, passed=1)  # the dusk view has its own time of day
    changed.stdout.fnmatch_lines(
        [f"*sky/default: FAIL: PSNR * (PSNR >= 40 dB, max |diff| <= 12); images in {report}/sky*"]
    )
    assert {"default-expected.png", "default-actual.png", "default-diff.png"} <= {
        p.name for p in (report / "sky").iterdir()
    }
    page = (report / "index.html").read_text()
    assert "2 views: 1 passed, 1 failed" in page


def test_a_bad_scene_or_view_name_fails_the_test_in_one_line(user_project):
    user_project.makepyfile(
        test_bad="""
def test_no_such_view(cloudview_check):
    cloudview_check("scenes/sky.toml", "noon")


def test_no_such_scene(cloudview_check):
    cloudview_check("scenes/none.toml")
"""
    )
    result = user_project.runpytest("test_bad.py")
    result.assert_outcomes(failed=2)
    result.stdout.fnmatch_lines(
        [
            "*cloudview: *sky.toml: views: no view named 'noon'; the scene has: default, dusk, along, impostors",
            "*cloudview: *none.toml: (file): no such file",
        ],
    )


def test_under_xdist_each_worker_renders_and_the_controller_writes_one_report(user_project):
    """`pytest -n 2`: the two views on two workers, each with its own GL context; the report lists both."""
    pytest.importorskip("xdist")
    user_project.runpytest("--cloudview-update-goldens").assert_outcomes(skipped=2)  # in this process: quicker
    report = user_project.path / "report"
    run = user_project.runpytest_subprocess("-n", "2", "--cloudview-report", str(report))
    run.assert_outcomes(passed=2)
    run.stdout.fnmatch_lines(["*2 workers*"])
    page = (report / "index.html").read_text()
    assert "2 views: 2 passed, 0 failed" in page
    assert {"sky/default-actual.png", "sky/dusk-actual.png"} <= {
        str(path.relative_to(report)) for path in report.rglob("*.png")
    }
