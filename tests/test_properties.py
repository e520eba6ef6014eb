"""Property-based checks (hypothesis) of the scene round trip and the shading contract."""

import numpy as np
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from cloudcore.scene import Camera, Cloud, Lighting, Scene, Shading
from cloudcore.scenefile import load_scene, save_scene
from cloudcore.shading import incident_light

finite = st.floats(-1e6, 1e6, allow_nan=False)
positive = st.floats(1e-6, 1e6, allow_nan=False, exclude_min=False)


@st.composite
def clouds(draw, index):
    n = draw(st.integers(0, 80))
    centres = draw(arrays(np.float64, (n, 3), elements=finite))
    radii = draw(arrays(np.float64, (n, 1), elements=positive))
    return Cloud(f"cloud{index}", np.hstack([centres, radii]),
                 optical_depth=draw(st.none() | st.floats(0, 1e6)),
                 albedo=draw(st.none() | st.floats(0, 1)))


@st.composite
def scenes(draw):
    count = draw(st.integers(0, 3))
    position = tuple(draw(st.lists(finite, min_size=3, max_size=3)))
    look_at = (position[0] + 1.0, position[1], position[2])
    return Scene(
        camera=Camera(position, look_at, draw(st.floats(1, 170))),
        lighting=Lighting(time_of_day=draw(st.floats(0, 24))),
        shading=Shading(draw(st.floats(0, 1)), draw(st.floats(0, 1e6)),
                        draw(st.sampled_from(["rayleigh", "henyey-greenstein", "cornette-shanks"])),
                        draw(st.floats(-0.999, 0.999))),
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
