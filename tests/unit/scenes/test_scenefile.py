"""Scene files: lossless round trips, clear refusals, atomic saves."""

import os
import subprocess
import sys
import tomllib
from dataclasses import replace

import numpy as np
import pytest

import cloudcore.scenes.files as scenefile
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import MAX_LAYERS, MAX_RINGS, Air, Scene, Shading
from cloudcore.scenes.files import load_scene, save_scene, scene_to_dict
from tests.conftest import VALLEY


def test_round_trip_is_lossless(tmp_path, small_scene):
    saved = save_scene(small_scene, tmp_path / "s.toml")
    loaded = load_scene(tmp_path / "s.toml")
    assert loaded == saved
    assert loaded.clouds[0].particles_file is None  # 12 particles stay inline
    assert loaded.clouds[1].particles_file == "s.particles/large.npy"
    for original, again in zip(small_scene.clouds, loaded.clouds):
        np.testing.assert_array_equal(original.particles, again.particles)  # bit for bit
    save_scene(loaded, tmp_path / "again.toml")
    assert (tmp_path / "again.toml").read_text().replace("again.particles", "s.particles") == (
        tmp_path / "s.toml"
    ).read_text()


def test_default_scene_round_trips(tmp_path):
    scene = load_scene(VALLEY)
    save_scene(scene, tmp_path / "valley.toml")
    assert load_scene(tmp_path / "valley.toml") == scene


def test_awkward_floats_survive(tmp_path, small_scene):
    from dataclasses import replace

    particles = np.array([[0.1 + 0.2, 1e-300, -2.5e11, 1e-6], [1 / 3, 5e-324, 1e6, 1e6]])
    scene = replace(small_scene, clouds=(replace(small_scene.clouds[0], particles=particles),))
    save_scene(scene, tmp_path / "f.toml")
    np.testing.assert_array_equal(load_scene(tmp_path / "f.toml").clouds[0].particles, particles)


BASE = """
[camera]
position = [0.0, 500.0, 1500.0]
look_at = [0.0, 800.0, 0.0]
[lighting]
time_of_day = 14.0
[[clouds]]
name = "a"
particles = [[0.0, 800.0, 0.0, 20.0], [10.0, 810.0, 0.0, 25.0]]
[[camera_paths]]
name = "p"
keys = [[0, 0, 500, 1500, 0, 800, 0], [5, 100, 500, 1500, 0, 800, 0]]
"""

MALFORMED = [
    # (old text, new text, field named in the error, problem named in the error)
    ("[0.0, 800.0, 0.0, 20.0]", "[0.0, 800.0, 0.0, -20.0]", "clouds[0].particles", "radius must be > 0"),
    ("[0.0, 800.0, 0.0, 20.0]", "[0.0, nan, 0.0, 20.0]", "clouds[0].particles", "not finite"),
    ("[0.0, 800.0, 0.0, 20.0]", "[0.0, 800.0, 20.0]", "clouds[0].particles", "rows of 4"),
    ("[0.0, 800.0, 0.0, 20.0]", '[0.0, "x", 0.0, 20.0]', "clouds[0].particles", "rows of 4"),
    ('name = "a"', 'name = "a"\noptical_depth = -1.0', "clouds[0].optical_depth", "within"),
    ('name = "a"', 'name = "a"\nalbedo = 1.5', "clouds[0].albedo", "within"),
    ('name = "a"', "", "clouds[0].name", "missing"),
    ('name = "a"', 'name = "a"\nparticles_file = "x.npy"', "clouds[0].particles", "exactly one"),
    ("time_of_day = 14.0", "time_of_day = 25.0", "lighting.time_of_day", "within"),
    ("time_of_day = 14.0", 'time_of_day = "noon"', "lighting.time_of_day", "expected a number"),
    ("time_of_day = 14.0", "time_of_day = inf", "lighting.time_of_day", "finite"),
    # the air (docs/atmosphere.md)
    ("time_of_day = 14.0", 'time_of_day = 14.0\nair = { sky = "blue" }', "lighting.air.sky", "physical"),
    (
        "time_of_day = 14.0",
        "time_of_day = 14.0\nair = { mie_density_scale = 101.0 }",
        "lighting.air.mie_density_scale",
        "within [0.0, 100.0]",
    ),
    (
        "time_of_day = 14.0",
        "time_of_day = 14.0\nair = { mie_density_scale = -1.0 }",
        "lighting.air.mie_density_scale",
        "within",
    ),
    (
        "time_of_day = 14.0",
        "time_of_day = 14.0\nair = { ground_albedo = 1.5 }",
        "lighting.air.ground_albedo",
        "within [0.0, 1.0]",
    ),
    ("time_of_day = 14.0", "time_of_day = 14.0\nair = { ground_albedo = nan }", "lighting.air.ground_albedo", "finite"),
    (
        "time_of_day = 14.0",
        "time_of_day = 14.0\nair = { origin_altitude_m = -10.0 }",
        "lighting.air.origin_altitude_m",
        "within [0.0, 50000.0]",
    ),
    (
        "time_of_day = 14.0",
        "time_of_day = 14.0\nair = { origin_altitude_m = 60000.0 }",
        "lighting.air.origin_altitude_m",
        "within",
    ),
    ("time_of_day = 14.0", "time_of_day = 14.0\nair = { turbidity = 2.0 }", "lighting.air.turbidity", "unknown key"),
    ("time_of_day = 14.0", "time_of_day = 14.0\nair = 3", "lighting.air", "expected a table"),
    ("[lighting]", '[shading]\nphase = "mie"\n[lighting]', "shading.phase", "rayleigh"),
    ("[lighting]", "[shading]\ng = 1.0\n[lighting]", "shading.g", "within"),
    ("[lighting]", "[shading]\noptical_depth = -8.0\n[lighting]", "shading.optical_depth", "within"),
    ("[lighting]", "[shading]\nalbedo = nan\n[lighting]", "shading.albedo", "finite"),
    ("[lighting]", "[shading]\nalbdo = 0.5\n[lighting]", "shading.albdo", "unknown key"),
    ("look_at = [0.0, 800.0, 0.0]", "look_at = [0.0, 500.0, 1500.0]", "camera.look_at", "differ"),
    ("look_at = [0.0, 800.0, 0.0]", "look_at = [0.0, 800.0]", "camera.look_at", "rows of 3"),
    ("[camera]", "[camera]\nfov_y_deg = 0.0", "camera.fov_y_deg", "within"),
    (
        "time_of_day = 14.0",
        "time_of_day = 14.0\n[[lighting.lights]]\ndirection = [0, 0, 0]",
        "lighting.lights[0].direction",
        "zero vector",
    ),
    ("[5, 100, 500", "[0, 100, 500", "camera_paths[0].keys", "increase strictly"),
    ('name = "p"', 'name = "p"\nspeed = 3', "camera_paths[0].speed", "unknown key"),
    ("[camera]", '[[objects]]\nname = "o"\nprimitive = "teapot"\n[camera]', "objects[0].primitive", "aircraft"),
    ("[camera]", '[[objects]]\nname = "o"\nprimitive = "box"\nscale = 0\n[camera]', "objects[0].scale", "within"),
    ("[camera]", '[[objects]]\nname = "o"\n[camera]', "objects[0].mesh", "exactly one"),
    ("[camera]", "[terrain]\nresolution = 1\n[camera]", "terrain.resolution", "within"),
    ("[camera]", "[terrain]\nsize = [100.0]\n[camera]", "terrain.size", "size_x"),
    ("[camera]", "[terrain]\nrelief = -1.0\n[camera]", "terrain.relief", "within [0.0, 8000.0]"),
    ("[camera]", "[terrain]\nrelief = 9000.0\n[camera]", "terrain.relief", "within"),
    ("[camera]", '[terrain]\nrelief = "high"\n[camera]', "terrain.relief", "expected a number"),
    ("[camera]", "[terrain]\nreach = -5.0\n[camera]", "terrain.reach", "within [0.0, 64000.0]"),
    ("[camera]", "[terrain]\nreach = 1e6\n[camera]", "terrain.reach", "within"),
    ("[camera]", "[terrain]\nreach = inf\n[camera]", "terrain.reach", "finite"),
    ("[camera]", "colour = 3\n[camera]", "colour", "unknown key"),
    ("[[camera_paths]]", '[[clouds]]\nname = "a"\nparticles = []\n[[camera_paths]]', "clouds[1].name", "duplicate"),
    ("[lighting]", "[lighting", "(toml)", "line"),
    # sprites and artist shading (Wang 2004, sections 3.2 and 5)
    ('name = "a"', 'name = "a"\nsprite = { rows = [4] }', "clouds[0].sprite.rows", "0..3"),
    ('name = "a"', 'name = "a"\nsprite = { rows = [] }', "clouds[0].sprite.rows", "one or more"),
    ('name = "a"', 'name = "a"\nsprite = { rows = [1.0] }', "clouds[0].sprite.rows", "integers"),
    (
        'name = "a"',
        'name = "a"\nsprite = { rotation_deg = [10.0, 0.0] }',
        "clouds[0].sprite.rotation_deg",
        "low <= high",
    ),
    (
        'name = "a"',
        'name = "a"\nsprite = { rotation_deg = [0.0, 400.0] }',
        "clouds[0].sprite.rotation_deg",
        "low + 360",
    ),
    ('name = "a"', 'name = "a"\nsprite = { rotation_deg = [0.0] }', "clouds[0].sprite.rotation_deg", "rows of 2"),
    ('name = "a"', 'name = "a"\nsprite = { facing = "up" }', "clouds[0].sprite.facing", "horizontal"),
    ('name = "a"', 'name = "a"\nsprite = { seed = -1 }', "clouds[0].sprite.seed", "within"),
    (
        'name = "a"',
        'name = "a"\nsprite = { flat_bottom_fraction = 1.5 }',
        "clouds[0].sprite.flat_bottom_fraction",
        "within [0, 1]",
    ),
    ('name = "a"', 'name = "a"\nsprite = { colour = 1 }', "clouds[0].sprite.colour", "unknown key"),
    ('name = "a"', 'name = "a"\nsprite = 3', "clouds[0].sprite", "expected a table"),
    (
        'name = "a"',
        'name = "a"\nartist = { levels = [[0, 1, 1, 1, 1], [1, 1, 1, 1, 1]] }',
        "clouds[0].artist.levels",
        "expected 5 levels",
    ),
    (
        'name = "a"',
        'name = "a"\nartist = { levels = [[0, 1, 1, 1, 1]' + ", [0.5, 1, 1, 1, 1]" * 3 + ", [1, 1, 1, 1, 1]] }",
        "clouds[0].artist.levels",
        "increase strictly",
    ),
    (
        'name = "a"',
        'name = "a"\nartist = { levels = [[0, 2, 1, 1, 1], [0.25, 1, 1, 1, 1], [0.5, 1, 1, 1, 1], '
        "[0.75, 1, 1, 1, 1], [1, 1, 1, 1, 1]] }",
        "clouds[0].artist.levels",
        "within [0, 1]",
    ),
    ('name = "a"', 'name = "a"\nartist = { levels = [[0, 1, 1, 1]] }', "clouds[0].artist.levels", "rows of 5"),
    (
        'name = "a"',
        'name = "a"\nartist = { level_percent_by_hour = [[24.0, 50.0]] }',
        "clouds[0].artist.level_percent_by_hour",
        "[0, 24)",
    ),
    (
        'name = "a"',
        'name = "a"\nartist = { level_percent_by_hour = [[12.0, -5.0]] }',
        "clouds[0].artist.level_percent_by_hour",
        ">= 0",
    ),
    (
        'name = "a"',
        'name = "a"\nartist = { directional_colour_by_hour = [[12.0, 1.0, "x", 1.0]] }',
        "clouds[0].artist.directional_colour_by_hour",
        "rows of 4",
    ),
    (
        'name = "a"',
        'name = "a"\nartist = { directional_range = [0.8, 0.5, 1.0] }',
        "clouds[0].artist.directional_range",
        "min <= median",
    ),
    (
        'name = "a"',
        'name = "a"\nartist = { directional_range = [0.1, nan, 1.0] }',
        "clouds[0].artist.directional_range",
        "not finite",
    ),
    ('name = "a"', 'name = "a"\nartist = { ambient = 1 }', "clouds[0].artist.ambient", "unknown key"),
    ('name = "a"', 'name = "a"\nshading_group_size = 0.0', "clouds[0].shading_group_size", "within"),
    # [cloud_field]: every limit of the field, checked on load
    ("[camera]", "[cloud_field]\nseed = -1\n[camera]", "cloud_field.seed", "within"),
    ("[camera]", "[cloud_field]\ncoverage = 1.5\n[camera]", "cloud_field.coverage", "within"),
    ("[camera]", "[cloud_field]\ncoverage = nan\n[camera]", "cloud_field.coverage", "finite"),
    ("[camera]", "[cloud_field]\ncell_size = 0.0\n[camera]", "cloud_field.cell_size", "within"),
    ("[camera]", "[cloud_field]\ncell_size = 1e9\n[camera]", "cloud_field.cell_size", "within"),
    ("[camera]", "[cloud_field]\nrings = 0\n[camera]", "cloud_field.rings", "within"),
    ("[camera]", f"[cloud_field]\nrings = {MAX_RINGS + 1}\n[camera]", "cloud_field.rings", "within"),
    ("[camera]", "[cloud_field]\nrings = 2.5\n[camera]", "cloud_field.rings", "integer"),
    ("[camera]", f"[cloud_field]\nlayers = {MAX_LAYERS + 1}\n[camera]", "cloud_field.layers", "within"),
    ("[camera]", "[cloud_field]\naltitude = [2000.0, 1000.0]\n[camera]", "cloud_field.altitude", "bottom < top"),
    ("[camera]", "[cloud_field]\naltitude = [1000.0]\n[camera]", "cloud_field.altitude", "rows of 2"),
    ("[camera]", '[cloud_field]\ncloud_type = "cumulus"\n[camera]', "cloud_field.cloud_type", "not one of"),
    ("[camera]", "[cloud_field]\nextent = [0.0, 40000.0]\n[camera]", "cloud_field.extent", "> 0"),
    ("[camera]", "[cloud_field]\nextent = [1e300, 40000.0]\n[camera]", "cloud_field.extent", "cells of cell_size"),
    ("[camera]", "[cloud_field]\ncentre = [inf, 0.0]\n[camera]", "cloud_field.centre", "not finite"),
    ("[camera]", "[cloud_field]\nwind = 3.0\n[camera]", "cloud_field.wind", "unknown key"),
]


@pytest.mark.parametrize("old, new, field, problem", MALFORMED)
def test_malformed_scene_names_file_field_and_problem(tmp_path, old, new, field, problem):
    assert old in BASE
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace(old, new, 1))
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    assert caught.value.source == str(path)
    assert caught.value.field == field
    assert problem in caught.value.problem
    assert str(caught.value).startswith(f"{path}: {field}: ")


def test_base_scene_is_valid(tmp_path):
    (tmp_path / "ok.toml").write_text(BASE)
    assert len(load_scene(tmp_path / "ok.toml").clouds) == 1


def test_a_byte_order_mark_from_a_windows_editor_is_accepted(tmp_path):
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + BASE.replace("\n", "\r\n").encode("utf-8"))
    (tmp_path / "plain.toml").write_text(BASE)
    assert load_scene(tmp_path / "bom.toml") == load_scene(tmp_path / "plain.toml")


def test_a_byte_order_mark_anywhere_but_the_start_is_still_refused(tmp_path):
    (tmp_path / "bad.toml").write_bytes(BASE.encode("utf-8") + b"\xef\xbb\xbf")
    with pytest.raises(SceneError) as caught:
        load_scene(tmp_path / "bad.toml")
    assert caught.value.field == "(toml)"


@pytest.mark.parametrize(
    "content, problem",
    [
        (None, "no such file"),
        (b"\x93NUMPY\x01\x00", "not a readable .npy"),
        ("truncated", "not a readable .npy"),
        ("3 columns", "rows of 4"),
        ("strings", "numeric array"),
        ("a folder", "is a folder, not a file"),
        ("a pipe", "not a regular file"),
        ("long doubles past float64", "not finite"),
    ],
)
def test_bad_particle_files_are_refused(tmp_path, content, problem, recwarn):
    """Each in one line, without a warning besides it; a pipe is refused, not read (the load blocked for ever)."""
    npy = tmp_path / "p.npy"
    if content == "a folder":
        npy.mkdir()
    elif content == "a pipe":
        os.mkfifo(npy)
    elif content == "long doubles past float64":
        if np.finfo(np.longdouble).max <= np.finfo(np.float64).max:
            pytest.skip("this platform's long double is a float64")
        np.save(npy, np.array([[0.0, 800.0, 0.0, 1.0]], dtype=np.longdouble) * np.longdouble("1e400"))
    elif content == "truncated":
        np.save(npy, np.ones((100, 4)))
        npy.write_bytes(npy.read_bytes()[:-37])
    elif content == "3 columns":
        np.save(npy, np.ones((5, 3)))
    elif content == "strings":
        np.save(npy, np.array(["a", "b"]))
    elif content is not None:
        npy.write_bytes(content)
    (tmp_path / "s.toml").write_text('[[clouds]]\nname = "c"\nparticles_file = "p.npy"\n')
    with pytest.raises(SceneError, match=problem) as caught:
        load_scene(tmp_path / "s.toml")
    assert caught.value.field == "clouds[0].particles_file"
    assert not [str(warning.message) for warning in recwarn]


@pytest.mark.parametrize("mesh, problem", [(".", "is a folder, not a file"), ("/dev/null", "not a regular file")])
def test_a_mesh_that_is_not_a_file_is_refused_as_such(tmp_path, mesh, problem):
    """It was "no such file" for both."""
    (tmp_path / "s.toml").write_text(f'[[objects]]\nname = "o"\nmesh = "{mesh}"\n')
    with pytest.raises(SceneError, match=problem) as caught:
        load_scene(tmp_path / "s.toml")
    assert caught.value.field == "objects[0].mesh"


def test_failed_save_leaves_the_previous_file_intact(tmp_path, small_scene, monkeypatch):
    path = tmp_path / "s.toml"
    save_scene(small_scene, path)
    before = path.read_bytes()

    def crash(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(scenefile.tomlkit, "dumps", crash)
    with pytest.raises(OSError):
        save_scene(small_scene, path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir() if p.suffix == ".tmp"] == []


def test_the_air_round_trips_and_a_file_without_it_gets_the_physical_sky(tmp_path, small_scene):
    assert small_scene.lighting.air == Air() and Air().sky == "physical"
    air = Air(sky="gradient", mie_density_scale=3.0, ground_albedo=0.1, origin_altitude_m=1500.0)
    scene = replace(small_scene, lighting=replace(small_scene.lighting, air=air))
    save_scene(scene, tmp_path / "air.toml")
    assert load_scene(tmp_path / "air.toml").lighting.air == air
    assert "air" not in scene_to_dict(small_scene)["lighting"]  # files of the default air stay as they were


def test_saved_document_is_plain_toml(tmp_path, small_scene):
    save_scene(small_scene, tmp_path / "s.toml")
    data = tomllib.loads((tmp_path / "s.toml").read_text())
    assert data["shading"]["phase"] == "henyey-greenstein"
    assert set(scene_to_dict(small_scene)) >= {"camera", "lighting", "shading", "clouds", "objects", "camera_paths"}


def test_cli_refuses_a_malformed_scene_in_one_line_with_status_2(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace("20.0]", "-20.0]", 1))
    result = subprocess.run([sys.executable, "-m", "cloudcore.cli", "shade", str(path)], capture_output=True, text=True)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        f"cloudview: error: {path}: clouds[0].particles: radius must be > 0 (row 0 has -20.0)"
    ]
    assert "Traceback" not in result.stderr


def test_sprites_and_artist_shading_round_trip(tmp_path):
    """Every preset's sprite style and artist model, and a shading group size, survive a save and load exactly."""
    from dataclasses import replace

    from cloudcore.artist.cloudgen import PRESETS, preset_cloud
    from cloudcore.model.scene import Scene

    clouds = tuple(preset_cloud(name, name, (3000.0 * i, 1000.0, 0.0), seed=i) for i, name in enumerate(PRESETS))
    clouds = (replace(clouds[0], shading_group_size=123.25),) + clouds[1:]
    saved = save_scene(Scene(clouds=clouds), tmp_path / "p.toml")
    loaded = load_scene(tmp_path / "p.toml")
    assert loaded == saved
    for cloud, again in zip(clouds, loaded.clouds):
        assert (again.sprite, again.artist, again.shading_group_size) == (
            cloud.sprite,
            cloud.artist,
            cloud.shading_group_size,
        )
    save_scene(loaded, tmp_path / "p.toml")
    assert load_scene(tmp_path / "p.toml") == loaded
    data = tomllib.loads((tmp_path / "p.toml").read_text())
    assert data["clouds"][0]["sprite"]["rows"] == [2, 2, 3]
    assert len(data["clouds"][0]["artist"]["levels"]) == 5


def test_a_cloud_without_sprite_or_artist_keeps_splats_and_harris(tmp_path):
    (tmp_path / "ok.toml").write_text(BASE)
    cloud = load_scene(tmp_path / "ok.toml").clouds[0]
    assert (cloud.sprite, cloud.artist, cloud.shading_group_size) == (None, None, None)
    assert set(scene_to_dict(load_scene(tmp_path / "ok.toml"))["clouds"][0]) == {"name", "particles", "color"}


def test_sprite_and_artist_tables_take_their_defaults(tmp_path):
    from cloudcore.model.cloud_records import ArtistShading, SpriteStyle

    (tmp_path / "d.toml").write_text(BASE.replace('name = "a"', 'name = "a"\nsprite = {}\nartist = {}', 1))
    cloud = load_scene(tmp_path / "d.toml").clouds[0]
    assert cloud.sprite == SpriteStyle() and cloud.artist == ArtistShading()


def test_the_eye_pass_is_kept_in_the_file_only_when_it_is_not_harris_s(tmp_path):
    scene = Scene(shading=Shading(eye_pass="saturated"))
    save_scene(scene, tmp_path / "s.toml")
    assert 'eye_pass = "saturated"' in (tmp_path / "s.toml").read_text()
    assert load_scene(tmp_path / "s.toml").shading.eye_pass == "saturated"
    save_scene(Scene(), tmp_path / "h.toml")
    assert "eye_pass" not in (tmp_path / "h.toml").read_text()
    (tmp_path / "bad.toml").write_text('[shading]\neye_pass = "magic"\n')
    with pytest.raises(SceneError, match="eye_pass"):
        load_scene(tmp_path / "bad.toml")
