import math
import os
from pathlib import Path

import numpy as np
import pytest

from cloudcore.model.cloud_records import ArtistShading, SpriteStyle
from cloudcore.model.scene import Camera, CameraPath, Cloud, Light, Lighting, Scene, SceneObject, Shading, Terrain, View
from cloudcore.resources import DEFAULT_SCENE

ROOT = Path(__file__).resolve().parents[1]
VALLEY = DEFAULT_SCENE
RENDER_WIDTH, RENDER_HEIGHT = 160, 120

# PyOpenGL picks its platform on first import: the tests render headless through EGL.
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
# every run of the editor or the command line a test starts plans from the same prior, not from a cost model a
# run before it fitted (`cloudcore.lod.costs.remembered_prior`; tests of the memory turn it on themselves)
os.environ["CLOUDVIEW_COST_MEMORY"] = "off"


@pytest.fixture(scope="session", autouse=True)
def cloudview_cache(request):
    """cloudview's disk cache (Yusov's tables) in pytest's own cache folder, never the real home: built
    once per checkout, kept between test runs."""
    folder = request.config.cache.mkdir("cloudview-cache")
    held = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(folder)
    yield folder
    if held is None:
        os.environ.pop("XDG_CACHE_HOME", None)
    else:
        os.environ["XDG_CACHE_HOME"] = held


@pytest.fixture(scope="session")
def renderer():
    """One headless renderer for all render tests; they skip where no EGL context can be made."""
    try:
        from cloudcore.gl import FrameRenderer

        frame_renderer = FrameRenderer(RENDER_WIDTH, RENDER_HEIGHT)
    except Exception as error:  # no libEGL or no Mesa driver: nothing here can render
        pytest.skip(f"no headless OpenGL (EGL) context: {error}")
    yield frame_renderer
    frame_renderer.close()


@pytest.fixture
def small_scene() -> Scene:
    """A scene that touches every field: inline and file particles, sprites and artist shading, explicit
    lights, objects, paths, views."""
    rng = np.random.default_rng(4)
    small = np.column_stack([rng.normal(size=(12, 3)) * 50 + [0, 800, 0], rng.uniform(10, 20, 12)])
    large = np.column_stack([rng.normal(size=(200, 3)) * 80 + [400, 900, 0], rng.uniform(15, 30, 200)])
    return Scene(
        camera=Camera((0.0, 500.0, 1500.0), (0.0, 800.0, 0.0), 55.0),
        lighting=Lighting(
            time_of_day=None,
            ambient=(0.1, 0.1, 0.12),
            lights=(Light((0.0, 1.0, 0.0), (1.0, 0.9, 0.8), 1.0), Light((0.6, 0.8, 0.0), (0.5, 0.6, 1.0), 0.3)),
        ),
        shading=Shading(albedo=0.8, optical_depth=6.5, phase="henyey-greenstein", g=0.7),
        clouds=(
            Cloud(
                "small",
                small,
                optical_depth=3.0,
                color=(1.0, 0.95, 0.9),
                sprite=SpriteStyle(rows=(0, 2, 2), rotation_deg=(-30.0, 200.0), seed=11, flat_bottom_fraction=0.2),
                artist=ArtistShading(directional_range=(0.1, 0.55, 0.9)),
                shading_group_size=40.0,
            ),
            Cloud("large", large, albedo=0.95),
        ),
        terrain=Terrain(size=(2000.0, 3000.0), resolution=33, height=300.0, seed=3),
        objects=(
            SceneObject("crate", primitive="box", scale=12.5, position=(10.0, 700.0, 5.0)),
            SceneObject("plane", primitive="aircraft", path=np.array([[0, 0, 900, 0], [10, 500, 900, 0]])),
        ),
        camera_paths=(CameraPath("orbit", np.array([[0, 0, 500, 1500, 0, 800, 0], [5, 1500, 600, 0, 0, 800, 0]])),),
        description="every field",
        views=(
            View(
                "noon_from_above",
                position=(0.0, 2000.0, 800.0),
                time_of_day=12.0,
                mode="auto",
                settings=(("tolerance_deg", 0.25), ("ring_radius", math.inf), ("group_clouds", False)),
                tolerance_psnr=35.0,
                max_diff=20,
            ),
            View("orbiting", camera_path="orbit", t=2.5, fov_y_deg=40.0, time_s=7.5),
        ),
    )


def assert_file_refused_in_one_line(path, field: str, problem: str) -> None:
    """Loading the scene file `path` raises one `SceneError` naming `field` and `problem`, in one line."""
    from cloudcore.model.errors import SceneError
    from cloudcore.scenes.files import load_scene

    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert (caught.value.field, caught.value.problem) == (field, problem)
    assert str(caught.value) == f"{path}: {field}: {problem}" and "\n" not in str(caught.value)


def pytest_collection_modifyitems(items):
    """Every test that asks for the shared renderer renders: marked `gl` (modules that render otherwise
    say so themselves with `pytestmark`)."""
    for item in items:
        if "renderer" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.gl)


def pytest_addoption(parser):
    parser.addoption(
        "--regenerate-goldens",
        action="store_true",
        help="rewrite tests/golden/*.png from the current renderer instead of comparing",
    )


def ball(centre, radius_m=250.0, particles=1000, seed=1) -> Cloud:
    """A round cloud of `particles` 40 m particles within `radius_m` of `centre`."""
    rng = np.random.default_rng(seed)
    offsets = rng.normal(size=(particles, 3))
    offsets *= (radius_m * rng.uniform(0.0, 1.0, particles) ** (1 / 3) / np.linalg.norm(offsets, axis=1))[:, None]
    return Cloud(f"ball {seed}", np.column_stack([np.asarray(centre) + offsets, np.full(particles, 40.0)]))
