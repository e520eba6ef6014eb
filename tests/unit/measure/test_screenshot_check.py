"""Screenshot tests without rendering: [[views]] in scene files, verdicts against goldens, goldens written only
when they change, the HTML report."""

import math
import re

import imageio.v3 as iio
import numpy as np
import pytest

from cloudcore.measure.imagecompare import compare
from cloudcore.measure.screenshot_check import (
    FAIL,
    MISSING,
    PASS,
    UNREADABLE,
    WRONG_SIZE,
    Tolerance,
    check_view,
    encode_png,
    find_view,
    keep_images,
    update_golden,
    view_camera,
    view_settings,
    write_report,
)
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Camera
from cloudcore.scenes.files import load_scene, save_scene, scene_from_dict, scene_to_dict

SCENE = {
    "camera": {"position": [0.0, 500.0, 1500.0], "look_at": [0.0, 800.0, 0.0], "fov_y_deg": 50.0},
    "camera_paths": [{"name": "pass", "keys": [[0.0, 0, 600, 2000, 0, 800, 0], [8.0, 0, 800, 200, 0, 800, -500]]}],
}


def scene_with(view: dict):
    return scene_from_dict(SCENE | {"views": [{"name": "v"} | view]}, "s.toml")


def test_views_round_trip_through_a_save(tmp_path, small_scene):
    save_scene(small_scene, tmp_path / "s.toml")
    loaded = load_scene(tmp_path / "s.toml")
    assert loaded.views == small_scene.views
    assert [view.name for view in loaded.all_views] == ["default", "noon_from_above", "orbiting"]
    # what a view leaves out stays out, so it follows the scene's camera
    assert "look_at" not in scene_to_dict(loaded)["views"][0]


def test_a_view_takes_what_it_leaves_out_from_the_scene_camera():
    scene = scene_with({"position": [100.0, 900.0, 1200.0], "time_of_day": 18.0})
    view = scene.views[0]
    assert view_camera(scene, view) == Camera((100.0, 900.0, 1200.0), (0.0, 800.0, 0.0), 50.0)
    assert view_camera(scene, scene.all_views[0]) == scene.camera
    on_path = scene_with({"camera_path": "pass", "t": 8.0, "fov_y_deg": 30.0})
    assert view_camera(on_path, on_path.views[0]) == Camera((0.0, 800.0, 200.0), (0.0, 800.0, -500.0), 30.0)


def test_view_settings_and_tolerance():
    scene = scene_with({"mode": "impostor", "settings": {"ring_radius": math.inf, "tolerance_px": 2.0}, "max_diff": 30})
    settings = view_settings(scene.views[0])
    assert (settings.mode, settings.ring_radius, settings.tolerance_px) == ("impostor", math.inf, 2.0)
    assert Tolerance(38.0, 10).for_view(scene.views[0]) == Tolerance(38.0, 30)
    assert view_settings(scene.all_views[0]).mode == "full"  # the default view is the reference picture
    chosen = scene_with({"mode": "auto", "settings": {"cloud_resolution_scale": "auto"}})
    assert view_settings(chosen.views[0]).cloud_resolution_scale == "auto"  # chosen per frame


@pytest.mark.parametrize(
    "view, field, problem",
    [
        ({"name": "default"}, "views[0].name", "is the scene's [camera]"),
        ({"name": "a/b"}, "views[0].name", "to name a golden file"),
        ({"name": ".hidden"}, "views[0].name", "to name a golden file"),
        ({"colour": 1}, "views[0].colour", "unknown key; valid keys: name, position"),
        ({"camera_path": "nowhere"}, "views[0].camera_path", "no camera path named 'nowhere'; the scene has: pass"),
        ({"camera_path": "pass", "position": [0, 1, 2]}, "views[0].camera_path", "not both"),
        ({"camera_path": "pass", "t": 9.0}, "views[0].t", "must be within [0.0, 8.0]"),
        ({"t": 1.0}, "views[0].t", "this view has none"),
        ({"look_at": [0.0, 500.0, 1500.0]}, "views[0].look_at", "must differ from position"),
        ({"position": [0.0, 800.0, 0.0]}, "views[0].position", "must differ from look_at (the scene camera's)"),
        ({"time_of_day": 25}, "views[0].time_of_day", "must be within [0.0, 24.0]"),
        ({"time_s": "noon"}, "views[0].time_s", "expected a number"),
        ({"mode": "fast"}, "views[0].mode", "'fast' is not one of: auto, full, impostor"),
        ({"settings": {"mode": "auto"}}, "views[0].settings.mode", "unknown key"),
        ({"settings": {"tolerance_deg": 200.0}}, "views[0].settings", "tolerance_deg must be within [0, 180]"),
        ({"settings": {"impostor_max_size": 300}}, "views[0].settings", "must be a power of two"),
        ({"settings": {"group_clouds": 1}}, "views[0].settings.group_clouds", "expected true or false"),
        ({"settings": {"transition_frames": 1.5}}, "views[0].settings.transition_frames", "expected an integer"),
        ({"settings": {"translation_metric": "x"}}, "views[0].settings.translation_metric", "is not one of"),
        ({"settings": {"ring_radius": math.nan}}, "views[0].settings.ring_radius", "must be finite"),
        ({"settings": {"cloud_resolution_scale": 2.0}}, "views[0].settings", "'auto' or within [0.125, 1], got 2.0"),
        ({"settings": {"cloud_resolution_scale": "often"}}, "views[0].settings.cloud_resolution_scale", "a number"),
        ({"tolerance_psnr": -1}, "views[0].tolerance_psnr", "must be within [0.0, inf]"),
        ({"max_diff": 256}, "views[0].max_diff", "must be within [0, 255]"),
        ({"fov_y_deg": 0.5}, "views[0].fov_y_deg", "must be within [1.0, 170.0]"),
    ],
)
def test_a_bad_view_is_refused_in_one_line(view, field, problem):
    with pytest.raises(SceneError) as caught:
        scene_from_dict(SCENE | {"views": [{"name": "v"} | view]}, "s.toml")
    assert caught.value.field == field and problem in caught.value.problem
    assert "\n" not in str(caught.value)


def test_view_names_are_unique():
    with pytest.raises(SceneError, match=r"views\[1\].name: duplicate name 'v'"):
        scene_from_dict(SCENE | {"views": [{"name": "v"}, {"name": "v"}]}, "s.toml")


def test_find_view_lists_the_views_there_are():
    with pytest.raises(SceneError, match="no view named 'x'; the scene has: default, v"):
        find_view(scene_with({}), "x", "s.toml")


@pytest.fixture
def image():
    y, x = np.mgrid[0:24, 0:32]
    return np.stack([x * 8, y * 10, (x + y) * 4], axis=-1).astype(np.uint8)


def test_verdicts(tmp_path, image):
    golden = tmp_path / "g.png"
    iio.imwrite(golden, image)
    assert check_view("s", "v", image, golden, Tolerance()).status == PASS
    nudged = image.copy()
    nudged[3, 4] += 13  # one pixel past the 12 levels: the PSNR alone would pass it
    result = check_view("s", "v", nudged, golden, Tolerance())
    assert result.status == FAIL and result.difference.psnr_db > 40
    assert result.line() == f"s/v: FAIL: {compare(nudged, image)} (PSNR >= 40 dB, max |diff| <= 12)"
    assert check_view("s", "v", nudged, golden, Tolerance(40.0, 13)).passed

    missing = check_view("s", "v", image, tmp_path / "none.png", Tolerance())
    assert missing.status == MISSING
    assert missing.line("cloudview check s.toml --update") == (
        f"s/v: no golden: {tmp_path / 'none.png'} does not exist; to write it: cloudview check s.toml --update"
    )
    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    unreadable = check_view("s", "v", image, tmp_path / "bad.png", Tolerance())
    assert unreadable.status == UNREADABLE and unreadable.problem.endswith("bad.png: not a readable image")
    iio.imwrite(tmp_path / "small.png", image[:10, :12])
    wrong = check_view("s", "v", image, tmp_path / "small.png", Tolerance())
    assert wrong.status == WRONG_SIZE and wrong.problem.endswith("small.png is 12x10, the view renders 32x24")


def test_a_golden_is_written_only_when_its_pixels_change(tmp_path, image):
    golden = tmp_path / "s" / "v.png"
    assert update_golden(check_view("s", "v", image, golden, Tolerance()), image)
    assert golden.read_bytes() == encode_png(image)
    before = golden.stat().st_mtime_ns
    assert not update_golden(check_view("s", "v", image, golden, Tolerance()), image)
    assert golden.stat().st_mtime_ns == before
    changed = image.copy()
    changed[0, 0] += 1  # within every tolerance, but not the same picture
    assert update_golden(check_view("s", "v", changed, golden, Tolerance()), changed)
    assert np.array_equal(iio.imread(golden), changed)
    assert list(golden.parent.iterdir()) == [golden]  # no temporary file left


def test_the_report_puts_failures_first_with_relative_links(tmp_path, image):
    goldens, report = tmp_path / "goldens", tmp_path / "report"
    goldens.mkdir()
    iio.imwrite(goldens / "same.png", image)
    darker = image // 2
    iio.imwrite(goldens / "darker.png", darker)
    entries = [
        keep_images(report, check_view("s", name, image, goldens / f"{name}.png", Tolerance()), image)
        for name in ("same", "darker", "missing")
    ]
    page = write_report(report, entries).read_text()
    rows = re.findall(r"<tr class='(\w+)'>.*?-actual.png", page)
    assert rows == ["fail", "fail", "pass"]
    assert page.index("missing-actual") < page.index("darker-actual") < page.index("same-actual")
    assert "3 views: 1 passed, 2 failed" in page
    links = re.findall(r"src='([^']+)'", page)
    assert sorted(links) == sorted(
        ["s/same-expected.png", "s/same-actual.png", "s/same-diff.png"]
        + ["s/darker-expected.png", "s/darker-actual.png", "s/darker-diff.png", "s/missing-actual.png"]
    )
    assert all((report / link).is_file() for link in links)
    assert np.array_equal(iio.imread(report / "s/darker-expected.png"), darker)
    assert "<script" in page and "http" not in page  # sorting is inline: the page works offline
