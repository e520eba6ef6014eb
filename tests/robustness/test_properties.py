"""Property-based checks (hypothesis) of the scene round trip, the loader's refusals and the shading contract."""

import math

import numpy as np
import pytest
import tomlkit
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from cloudcore.light.phase import MAX_ABS_G, PHASE_NAMES
from cloudcore.light.shading import incident_light
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Camera, Cloud, Lighting, Scene, Shading
from cloudcore.scenes.files import load_scene, save_scene, scene_to_dict

finite = st.floats(-1e6, 1e6, allow_nan=False)
positive = st.floats(1e-6, 1e6, allow_nan=False, exclude_min=False)


@st.composite
def clouds(draw, index):
    n = draw(st.integers(0, 80))
    centres = draw(arrays(np.float64, (n, 3), elements=finite))
    radii = draw(arrays(np.float64, (n, 1), elements=positive))
    return Cloud(
        f"cloud{index}",
        np.hstack([centres, radii]),
        optical_depth=draw(st.none() | st.floats(0, 1e6)),
        albedo=draw(st.none() | st.floats(0, 1)),
    )


@st.composite
def scenes(draw):
    count = draw(st.integers(0, 3))
    position = tuple(draw(st.lists(finite, min_size=3, max_size=3)))
    look_at = (position[0] + 1.0, position[1], position[2])
    return Scene(
        camera=Camera(position, look_at, draw(st.floats(1, 170))),
        lighting=Lighting(time_of_day=draw(st.floats(0, 24))),
        shading=Shading(
            draw(st.floats(0, 1)),
            draw(st.floats(0, 1e6)),
            draw(st.sampled_from(["rayleigh", "henyey-greenstein", "cornette-shanks"])),
            draw(st.floats(-0.999, 0.999)),
        ),
        clouds=tuple(draw(clouds(i)) for i in range(count)),
    )


@settings(max_examples=40, deadline=None)
@given(scene=scenes())
def test_random_valid_scenes_save_and_reload_identically(tmp_path_factory, scene):
    path = tmp_path_factory.mktemp("round") / "scene.toml"
    saved = save_scene(scene, path)
    assert load_scene(path) == saved
    for original, again in zip(scene.clouds, saved.clouds):
        np.testing.assert_array_equal(original.particles, again.particles)


def outside(low: float, high: float):
    """Floats out of [low, high], NaN and the infinities included."""
    return st.floats().filter(lambda value: not low <= value <= high)


not_finite = st.sampled_from([math.nan, math.inf, -math.inf])


@st.composite
def bad_rows(draw, rows: list):
    """Particle rows with one radius <= 0 or one coordinate not finite."""
    rows = [list(row) for row in rows]
    row, column = draw(st.integers(0, len(rows) - 1)), draw(st.integers(0, 3))
    rows[row][column] = draw(not_finite | st.floats(max_value=0.0)) if column == 3 else draw(not_finite)
    return rows


@st.composite
def invalid_documents(draw):
    """(a random valid scene's TOML document with one value made invalid, the field that value is at)."""
    document = scene_to_dict(draw(scenes()))
    mistakes = [
        (("camera", "fov_y_deg"), outside(1.0, 170.0)),
        (
            ("camera", "position"),
            st.lists(finite, max_size=5).filter(lambda v: len(v) != 3)
            | st.tuples(finite, not_finite, finite).map(list),
        ),
        (("lighting", "time_of_day"), outside(0.0, 24.0)),
        (("shading", "albedo"), outside(0.0, 1.0)),
        (("shading", "optical_depth"), st.floats(max_value=-1e-300) | not_finite),
        (("shading", "phase"), st.text(max_size=20).filter(lambda name: name not in PHASE_NAMES)),
        (("shading", "g"), outside(-MAX_ABS_G, MAX_ABS_G)),
    ]
    for index, cloud in enumerate(document.get("clouds", [])):
        mistakes.append((("clouds", index, "albedo"), outside(0.0, 1.0)))
        if cloud["particles"]:
            mistakes.append((("clouds", index, "particles"), bad_rows(cloud["particles"])))
    path, values = draw(st.sampled_from(mistakes))
    table = document
    for step in path[:-1]:
        table = table[step]
    table[path[-1]] = draw(values)
    return document, "".join(f"[{step}]" if isinstance(step, int) else f".{step}" for step in path).lstrip(".")


@settings(max_examples=80, deadline=None)
@given(invalid=invalid_documents())
def test_random_invalid_scenes_are_refused_naming_the_field(tmp_path_factory, invalid):
    document, field = invalid
    path = tmp_path_factory.mktemp("invalid") / "scene.toml"
    path.write_text(tomlkit.dumps(document), encoding="utf-8")
    with pytest.raises(SceneError) as refused:
        load_scene(path)
    message = str(refused.value)
    assert refused.value.field == field, message
    assert message.startswith(f"{path}: {field}: ") and len(message.splitlines()) == 1


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 40),
    seed=st.integers(0, 2**32 - 1),
    tau=st.floats(0, 1e6),
    albedo=st.floats(0, 1),
    scale=st.floats(1e-6, 1e6),
    light=st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3),
    method=st.sampled_from(["exact", "raster"]),
)
def test_shading_is_finite_and_within_0_1(n, seed, tau, albedo, scale, light, method):
    rng = np.random.default_rng(seed)
    positions = rng.normal(size=(n, 3)) * scale
    radii = rng.uniform(0.2, 2.0, n) * scale
    got = incident_light(positions, radii, tau, albedo, light, method=method)
    assert got.shape == (n,)
    assert np.all(np.isfinite(got)) and np.all((got >= 0) & (got <= 1))
