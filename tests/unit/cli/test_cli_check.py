"""`cloudview check`: every view of every scene against its golden; planted changes fail with the diff where
they are, `--update` makes them pass, broken goldens say so, the same view renders the same bytes."""

import dataclasses
import math

import imageio.v3 as iio
import numpy as np
import pytest

from cloudcore.cli import main
from cloudcore.measure.screenshot_check import Tolerance, check_view, encode_png, view_camera
from cloudcore.model.scene import Air, Camera, CameraPath, Cloud, Lighting, Scene, View
from cloudcore.resources import resource_path
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.stats.overlays import to_pixels
from tests.conftest import ROOT

pytestmark = pytest.mark.gl

SIZE = (96, 72)
#: the views of a shipped example scene, checked as a user's CI would check theirs; regenerated on purpose with
#:   cloudview check cloudcore/resources/scenes/aircraft_in_cloud.toml --goldens tests/check_goldens \
#:       --size 160x120 --update
EXAMPLE = resource_path("scenes", "aircraft_in_cloud.toml")
EXAMPLE_GOLDENS = ROOT / "tests" / "check_goldens"
VIEWS = ("default", "dusk", "along", "impostors")


def blob(centre, count, seed) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.normal(size=(count, 3)) * 90 + centre, rng.uniform(80, 120, count)])


def sky_scene() -> Scene:
    """Two small clouds apart in an empty sky, with three views besides the default; the gradient sky, whose colour
    is the same from 09:00 to 14:00 (the atmosphere's follows the sun), so a changed time of day changes the
    clouds alone."""
    return Scene(
        camera=Camera((0.0, 800.0, 1600.0), (0.0, 800.0, 0.0), 50.0),
        lighting=Lighting(14.0, air=Air(sky="gradient")),
        clouds=(Cloud("left", blob([-400, 800, 0], 12, 1)), Cloud("right", blob([400, 800, 0], 12, 2))),
        camera_paths=(CameraPath("pass", np.array([[0, -300, 700, 2000, 0, 800, 0], [4, 300, 900, 1600, 0, 800, 0]])),),
        views=(
            View("dusk", time_of_day=18.4),
            View("along", camera_path="pass", t=3.0),
            View("impostors", position=(0.0, 1400.0, 1600.0), mode="impostor", settings=(("ring_radius", math.inf),)),
        ),
    )


@pytest.fixture
def project(tmp_path):
    """A scene folder with its goldens made by `--update`."""
    scene = tmp_path / "scenes" / "sky.toml"
    save_scene(sky_scene(), scene)
    check(tmp_path, "--update")
    return tmp_path


def check(root, *options, scenes=None):
    """`cloudview check` on the project's scenes at SIZE; its exit status."""
    arguments = [str(root / "scenes")] if scenes is None else scenes
    return main(["check", *arguments, "--goldens", str(root / "goldens"), "--size", "96x72", *options])


def lines(capsys) -> list[str]:
    return capsys.readouterr().out.splitlines()


def splat_box(cloud: Cloud, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """The screen box, (x, y) low and high in pixels, that the cloud's splats can reach (twice their radius:
    a splat's Gaussian tail)."""
    centres, _ = to_pixels(cloud.centres, camera, SIZE)
    focal = (SIZE[1] / 2) / math.tan(math.radians(camera.fov_y_deg / 2))
    distances = np.linalg.norm(cloud.centres - camera.position, axis=1)
    reach = 2.0 * focal * (cloud.radii / distances).max() + 1.0
    return centres.min(axis=0) - reach, centres.max(axis=0) + reach


def in_box(pixels: np.ndarray, box) -> np.ndarray:
    """Which of the (row, column) `pixels` lie in the box."""
    low, high = box
    rows, columns = pixels[:, 0], pixels[:, 1]
    return (columns >= low[0]) & (columns <= high[0]) & (rows >= low[1]) & (rows <= high[1])


def report_diff(root, view: str) -> np.ndarray:
    """(row, column) of the pixels the report's diff image of the view shows off by 3 levels or more."""
    diff = iio.imread(root / "report" / "sky" / f"{view}-diff.png")[..., 0]
    return np.argwhere(diff >= 8 * 3)


def test_update_writes_the_goldens_then_every_view_passes(tmp_path, capsys):
    save_scene(sky_scene(), tmp_path / "scenes" / "sky.toml")
    assert check(tmp_path) == 1  # no goldens yet
    first = lines(capsys)
    assert first[0].startswith("sky/default: no golden: ") and first[0].endswith(
        f"to write it: cloudview check {tmp_path / 'scenes'} --goldens {tmp_path / 'goldens'} --size 96x72 --update"
    )
    assert first[-1] == "4 views: 0 passed, 4 failed"

    assert check(tmp_path, "--update") == 0
    assert lines(capsys)[-1] == f"4 of 4 goldens changed, in {tmp_path / 'goldens'}"
    goldens = {view: tmp_path / "goldens" / "sky" / f"{view}.png" for view in VIEWS}
    for golden in goldens.values():
        image = iio.imread(golden)
        assert image.shape == (72, 96, 3) and image.std() > 1.0  # each view shows something

    assert check(tmp_path) == 0
    output = lines(capsys)
    assert [line.split(": ")[:2] for line in output[:-1]] == [[f"sky/{view}", "pass"] for view in VIEWS]
    assert output[-1] == "4 views: 4 passed, 0 failed"

    modified = {view: golden.stat().st_mtime_ns for view, golden in goldens.items()}
    assert check(tmp_path, "--update") == 0
    assert lines(capsys)[-1].startswith("0 of 4 goldens changed")
    assert {view: golden.stat().st_mtime_ns for view, golden in goldens.items()} == modified  # not rewritten


def test_a_changed_time_of_day_fails_the_views_that_take_it_until_updated(project, capsys):
    scene_file = project / "scenes" / "sky.toml"
    scene = load_scene(scene_file)
    save_scene(dataclasses.replace(scene, lighting=dataclasses.replace(scene.lighting, time_of_day=9.0)), scene_file)
    assert check(project, "--report", str(project / "report")) == 1
    verdicts = {line.split(": ")[0]: line.split(": ")[1] for line in lines(capsys)[:-2]}
    # the dusk view has a time of its own: the scene's does not reach it
    assert verdicts == {"sky/default": "FAIL", "sky/dusk": "pass", "sky/along": "FAIL", "sky/impostors": "FAIL"}
    # from 14:00 to 09:00 the sky keeps its colour: the change is the light on the two clouds, on both
    changed = report_diff(project, "default")
    camera = view_camera(scene, scene.all_views[0])
    left, right = (in_box(changed, splat_box(cloud, camera)) for cloud in scene.clouds)
    assert left.any() and right.any() and np.all(left | right)

    assert check(project, "--update") == 0
    assert lines(capsys)[-1].startswith("3 of 4 goldens changed")
    assert check(project) == 0


def test_one_moved_particle_fails_with_the_diff_on_its_cloud(project, capsys):
    scene_file = project / "scenes" / "sky.toml"
    scene = load_scene(scene_file)
    right = scene.clouds[1]
    particles = right.particles.copy()
    particles[0, :3] += (0.0, 250.0, 0.0)  # out of the cloud, above it
    save_scene(
        dataclasses.replace(scene, clouds=(scene.clouds[0], dataclasses.replace(right, particles=particles))),
        scene_file,
    )

    assert check(project, "--report", str(project / "report")) == 1
    output = lines(capsys)
    assert output[0].startswith("sky/default: FAIL: PSNR ")
    changed = report_diff(project, "default")
    camera = view_camera(scene, scene.all_views[0])
    # the particle's own cloud changed (its light too: the particle shadows its neighbours), the other did not
    moved = dataclasses.replace(right, particles=np.vstack([right.particles, particles[:1]]))  # before and after
    assert len(changed) > 0 and np.all(in_box(changed, splat_box(moved, camera)))
    left_centres = to_pixels(scene.clouds[0].centres, camera, SIZE)[0]
    assert changed[:, 1].min() > left_centres[:, 0].max()
    # and the change is where the particle was and where it is now
    for place in (right.particles[0, :3], particles[0, :3]):
        at = to_pixels(place, camera, SIZE)[0][0]
        assert np.abs(changed[:, ::-1] - at).max(axis=1).min() <= 2

    assert check(project, "--update") == 0
    assert check(project) == 0


def test_missing_corrupt_and_wrong_sized_goldens_each_give_a_clear_line(project, capsys):
    goldens = project / "goldens" / "sky"
    (goldens / "default.png").unlink()
    (goldens / "dusk.png").write_bytes(b"not a png")
    iio.imwrite(goldens / "along.png", np.zeros((10, 12, 3), np.uint8))
    assert check(project, "--report", str(project / "report")) == 1
    output = lines(capsys)
    update = (
        f"; to write it: cloudview check {project / 'scenes'} --goldens {project / 'goldens'} --size 96x72 --update"
    )
    assert output[0] == f"sky/default: no golden: {goldens / 'default.png'} does not exist{update}"
    assert output[1] == f"sky/dusk: unreadable golden: {goldens / 'dusk.png'}: not a readable image{update}"
    assert output[2] == f"sky/along: wrong size: {goldens / 'along.png'} is 12x10, the view renders 96x72{update}"
    assert output[3].startswith("sky/impostors: pass: ")
    assert output[4] == "4 views: 1 passed, 3 failed"
    assert (project / "report" / "index.html").is_file()
    assert (project / "report" / "sky" / "default-actual.png").is_file()

    assert check(project, "--update") == 0
    assert lines(capsys)[-1].startswith("3 of 4 goldens changed")
    assert check(project) == 0


def test_the_same_view_renders_the_same_bytes_whatever_came_before(tmp_path):
    from cloudcore.gl.views import ViewRenderer

    scene = sky_scene()
    with ViewRenderer() as renderer:
        forward = [encode_png(renderer.render(scene, view, SIZE)) for view in scene.all_views]
        backward = [encode_png(renderer.render(scene, view, SIZE)) for view in reversed(scene.all_views)]
    assert forward == backward[::-1]
    assert len(set(forward)) == len(forward)  # four different pictures


def test_bad_input_is_one_line_and_status_2(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    assert check(tmp_path, scenes=[str(tmp_path / "empty")]) == 2
    assert capsys.readouterr().err == f"cloudview: error: {tmp_path / 'empty'}: (folder): holds no scene (*.toml)\n"
    assert check(tmp_path, scenes=[str(tmp_path / "none.toml")]) == 2
    assert capsys.readouterr().err == f"cloudview: error: {tmp_path / 'none.toml'}: (file): no such file\n"
    for folder in ("a", "b"):
        save_scene(sky_scene(), tmp_path / folder / "sky.toml")
    assert check(tmp_path, scenes=[str(tmp_path / "a"), str(tmp_path / "b")]) == 2
    assert "their goldens would be one folder" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exited:
        main(["check", str(tmp_path / "a"), "--goldens", str(tmp_path / "g"), "--size", "96"])
    assert exited.value.code == 2 and "invalid frame_size value: '96'" in capsys.readouterr().err


def test_the_example_scene_matches_its_committed_goldens(capsys):
    assert main(["check", str(EXAMPLE), "--goldens", str(EXAMPLE_GOLDENS), "--size", "160x120"]) == 0
    output = lines(capsys)
    assert [line.split(": ")[:2] for line in output[:-1]] == [
        [f"aircraft_in_cloud/{view}", "pass"] for view in ("default", "sunset", "aircraft_inside", "orbit_quarter")
    ]
    # the view at 10 s on the scene clock has the aircraft in the cloud's heart, where the default view at 0 s has not:
    # in the cloud's shadow it is dim, 10 levels from the cloud around it at most (the default tolerance's 12 would
    # not tell them apart), so a tolerance of 5 is asked
    inside = iio.imread(EXAMPLE_GOLDENS / "aircraft_in_cloud" / "aircraft_inside.png")
    default = EXAMPLE_GOLDENS / "aircraft_in_cloud" / "default.png"
    assert not check_view("a", "v", inside, default, Tolerance(max_diff=5)).passed
