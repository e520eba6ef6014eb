"""Terrain from a heightmap: a 16-bit greyscale PNG or a GeoTIFF of elevations read whole, sampled bilinearly,
meshed into the same tiles and coloured by height and slope; every bad file or key refused with one line naming
the file and the problem."""

import dataclasses
import io
import struct
import zlib

import numpy as np
import pytest

from cloudcore.cli import main
from cloudcore.model.errors import SceneError
from cloudcore.model.scene import HeightGrid, Terrain
from cloudcore.resources import DEFAULT_SCENE, resource_path
from cloudcore.scenes.files import load_scene, save_scene, scene_from_dict
from cloudcore.scenes.interop.heightmap import MAX_HEIGHTMAP_SIDE, read_heightmap, write_heightmap
from cloudcore.world.terrain import ground_colours, height_at, heightfield_mesh, highest_ground_m
from cloudcore.world.terrain_tiles import TILE_CELLS, leaf_tiles, tile_frame, tile_meshes

EXAMPLE = resource_path("scenes", "heightmap_valley.toml")


def heightmap_scene(folder, heights, **terrain_keys) -> dict:
    """A scene dict of a heightmap terrain whose PNG (`heights`) is written into `folder`."""
    write_heightmap(folder / "ground.png", heights)
    terrain = {"kind": "heightmap", "heightmap": "ground.png", "size": [1000.0, 500.0], "height": 200.0}
    return {"terrain": terrain | terrain_keys}


def test_sixteen_bits_are_read_whole(tmp_path):
    levels = np.arange(0, 65536, 257, dtype=np.float64)[:256].reshape(16, 16) / 65535.0
    levels[0, :3] = [1 / 65535, 2 / 65535, 65534 / 65535]  # neighbouring 16-bit levels, which 8 bits would merge
    write_heightmap(tmp_path / "levels.png", levels)
    assert np.array_equal(read_heightmap(tmp_path / "levels.png"), levels)


def test_heights_are_bilinear_between_the_pixels_and_held_past_the_edges(tmp_path):
    grid = np.array([[0.0, 1.0, 0.5], [0.25, 0.75, 0.0]])
    scene = scene_from_dict(heightmap_scene(tmp_path, grid), base_dir=tmp_path)
    terrain = scene.terrain
    # pixel centres: columns at x = -500, 0, 500, rows at z = -250, 250
    assert np.allclose(height_at(terrain, [-500.0, 0.0, 500.0], [-250.0] * 3), 200.0 * grid[0], atol=0.01)
    assert height_at(terrain, -250.0, 0.0) == pytest.approx(200.0 * np.mean(grid[:, :2]), abs=0.01)
    assert height_at(terrain, 250.0, -125.0) == pytest.approx(200.0 * (0.75 * 0.75 + 0.375 * 0.25), abs=0.01)
    assert height_at(terrain, 5000.0, -9000.0) == pytest.approx(200.0 * grid[0, -1], abs=0.01)
    assert highest_ground_m(terrain) == pytest.approx(200.0)


def test_the_tiles_mesh_a_heightmap_at_its_pixels(tmp_path):
    """The finest tiles' cells are the image's pixels, their vertices its heights; the tiles' frame stands on its
    highest sample."""
    rng = np.random.default_rng(3)
    scene = scene_from_dict(heightmap_scene(tmp_path, rng.uniform(0.0, 0.5, (9, 33))), base_dir=tmp_path)
    terrain = scene.terrain
    frame = tile_frame(terrain)
    assert frame.cell_m == pytest.approx(1000.0 / 32)  # 33 columns over 1000 m, finer than 9 rows over 500 m
    assert frame.top_m == pytest.approx(200.0 * terrain.heights.values.max())
    tiles = leaf_tiles(frame, (0.0, 10.0, 0.0))
    positions, normals = tile_meshes(terrain, frame, tiles)
    grid = positions[:, : (TILE_CELLS + 1) ** 2].reshape(-1, 3)
    assert np.allclose(grid[:, 1], height_at(terrain, grid[:, 0], grid[:, 2]))
    assert np.all(normals[..., 1] > 0.0)
    vertices, faces = heightfield_mesh(terrain)
    assert vertices.shape == (33 * 9, 3) and faces.shape == (2 * 32 * 8, 3)


def test_ground_colours_follow_the_ramp_by_height_and_turn_steep_with_the_slope():
    terrain = Terrain(
        color_ramp=((0.0, 0.0, 0.5, 0.0), (100.0, 1.0, 1.0, 1.0)),
        steep_color=(0.5, 0.0, 0.0),
        steep_slope_deg=(30.0, 50.0),
    )
    up = [0.0, 1.0, 0.0]
    positions = np.array([[0.0, -10.0, 0.0], [0.0, 50.0, 0.0], [0.0, 500.0, 0.0]])
    assert np.allclose(ground_colours(terrain, positions, [up] * 3), [[0, 0.5, 0], [0.5, 0.75, 0.5], [1, 1, 1]])
    tilted = [[np.sin(np.radians(a)), np.cos(np.radians(a)), 0.0] for a in (20.0, 40.0, 60.0)]
    colours = ground_colours(terrain, [[0.0, 100.0, 0.0]] * 3, tilted)
    assert np.allclose(colours, [[1, 1, 1], [0.75, 0.5, 0.5], [0.5, 0, 0]])
    plain = Terrain()
    assert np.array_equal(ground_colours(plain, positions, [up] * 3), np.tile(plain.color, (3, 1)))


def test_the_example_scene_loads_and_saves_back_the_same(tmp_path):
    scene = load_scene(EXAMPLE)
    terrain = scene.terrain
    assert terrain.kind == "heightmap" and terrain.heights.values.shape == (257, 257)
    assert len(terrain.color_ramp) > 1 and terrain.steep_color is not None
    # the valley's hills, from the image, within its 16 bits and the bilinear step between its pixels
    valley = dataclasses.replace(load_scene(DEFAULT_SCENE).terrain, relief=0.0)
    x, z = np.meshgrid(np.linspace(-3000, 3000, 257), np.linspace(-3000, 3000, 257))
    assert np.allclose(height_at(dataclasses.replace(terrain, relief=0.0), x, z), height_at(valley, x, z), atol=0.01)
    scene = dataclasses.replace(scene, clouds=())
    save_scene(scene, tmp_path / "again.toml")  # another folder: the image goes along
    assert (tmp_path / "heightmap_valley.png").exists()
    assert load_scene(tmp_path / "again.toml") == scene


def test_saving_beside_another_image_of_that_name_keeps_it_and_writes_the_scenes_own(tmp_path):
    scene = load_scene(EXAMPLE)
    other = tmp_path / "heightmap_valley.png"
    write_heightmap(other, np.zeros((4, 4)))
    before = other.read_bytes()
    saved = save_scene(scene, tmp_path / "mine.toml")
    assert other.read_bytes() == before and saved.terrain.heightmap == "mine.heightmap.png"
    assert load_scene(tmp_path / "mine.toml").terrain.heights == scene.terrain.heights
    assert save_scene(scene, tmp_path / "mine.toml").terrain.heightmap == "mine.heightmap.png"  # found, not again


def png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_claiming(width: int, height: int, depth: int = 16, colour_type: int = 0) -> bytes:
    """A PNG signature and header claiming an image, and no pixels."""
    header = png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 0))
    return b"\x89PNG\r\n\x1a\n" + header + png_chunk(b"IEND", b"")


#: GeoKey directories: a projected model in metres, a geographic one (degrees)
PROJECTED_IN_METRES = (1, 1, 0, 2, 1024, 0, 1, 1, 3076, 0, 1, 9001)
GEOGRAPHIC = (1, 1, 0, 1, 1024, 0, 1, 2)


def geotiff_bytes(elevations, scale=None, keys=None, tie=None, no_data=None) -> bytes:
    """A one-band float32 GeoTIFF of `elevations`, with the pixel `scale` (x, y), GeoKey directory `keys`, tie
    point (x, y) of its top left pixel and GDAL's no-data value where given."""
    from PIL import Image, TiffImagePlugin

    tags = TiffImagePlugin.ImageFileDirectory_v2()
    for tag, value, kind in (
        (33550, None if scale is None else (*scale, 0.0), 12),
        (33922, None if tie is None else (0.0, 0.0, 0.0, *tie, 0.0), 12),
        (34735, keys, 3),
        (42113, no_data, 2),
    ):
        if value is not None:
            tags[tag], tags.tagtype[tag] = value, kind
    out = io.BytesIO()
    Image.fromarray(np.asarray(elevations, dtype=np.float32), mode="F").save(
        out, format="TIFF", tiffinfo=tags, compression="tiff_deflate"
    )
    return out.getvalue()


def tiff_claiming(width: int, height: int) -> bytes:
    """A little-endian TIFF header and first directory claiming a 16-bit grey image, and no pixels."""
    entries = [(256, 4, width), (257, 4, height), (258, 3, 16), (259, 3, 1), (262, 3, 1), (273, 4, 0), (277, 3, 1)]
    directory = struct.pack("<H", len(entries)) + b"".join(
        struct.pack("<HHII", tag, kind, 1, value) for tag, kind, value in entries
    )
    return b"II*\x00" + struct.pack("<I", 8) + directory + struct.pack("<I", 0)


def rgb_tiff_bytes() -> bytes:
    from PIL import Image

    out = io.BytesIO()
    Image.new("RGB", (16, 16), (90, 120, 60)).save(out, format="TIFF")
    return out.getvalue()


def with_holes(value: float) -> np.ndarray:
    elevations = np.linspace(200.0, 900.0, 4096).reshape(64, 64)
    elevations[[3, 10, 40], [5, 60, 2]] = value
    return elevations


def bad_file(folder, name: str, content: bytes) -> str:
    (folder / name).write_bytes(content)
    return name


BAD_HEIGHTMAPS = {
    "not a PNG": (lambda d: bad_file(d, "ground.png", b"GIF89a" + bytes(64)), "neither a PNG nor a TIFF file"),
    "truncated": (
        lambda d: bad_file(d, "ground.png", (d.parent / "good.png").read_bytes()[:-400]),
        "not a readable PNG (truncated or corrupt?)",
    ),
    "10^12 pixels claimed": (
        lambda d: bad_file(d, "ground.png", png_claiming(1_000_000, 1_000_000)),
        f"1000000x1000000 pixels (1e+12), each side must be within [2, {MAX_HEIGHTMAP_SIDE}]",
    ),
    "colour": (
        lambda d: bad_file(d, "ground.png", png_claiming(64, 64, 8, 2)),
        "expected 8- or 16-bit greyscale, got colour type 2",
    ),
    "corrupt header": (
        lambda d: bad_file(d, "ground.png", png_claiming(64, 64)[:29] + b"\0\0\0\0"),
        "its header chunk is corrupt (CRC mismatch)",
    ),
    "TIFF truncated": (
        lambda d: bad_file(d, "dem.tif", geotiff_bytes(np.arange(4096.0).reshape(64, 64))[:-3000]),
        "not a readable TIFF (truncated or corrupt?)",
    ),
    "TIFF of 10^12 pixels claimed": (
        lambda d: bad_file(d, "dem.tif", tiff_claiming(1_000_000, 1_000_000)),
        f"each side must be within [2, {MAX_HEIGHTMAP_SIDE}]",
    ),
    "TIFF in colour": (
        lambda d: bad_file(d, "dem.tif", rgb_tiff_bytes()),
        "expected one band of elevations, got Pillow's mode 'RGB'",
    ),
    "TIFF with no-data samples": (
        lambda d: bad_file(d, "dem.tif", geotiff_bytes(with_holes(-9999.0), no_data="-9999")),
        "3 of its 4,096 samples hold no elevation (no-data or not finite): fill them first",
    ),
    "TIFF with NaN": (
        lambda d: bad_file(d, "dem.tif", geotiff_bytes(with_holes(np.nan))),
        "3 of its 4,096 samples hold no elevation",
    ),
    "missing": (lambda d: "nowhere.png", "no such file"),
    "outside the folder": (lambda d: "../good.png", "leads outside the scene file's folder"),
    "absolute": (lambda d: str(d / "good.png"), "must be relative to the scene file's folder, not absolute"),
}


@pytest.mark.parametrize("case", BAD_HEIGHTMAPS)
def test_a_bad_heightmap_is_one_line_naming_the_file_and_the_problem(tmp_path, case, capsys):
    make, problem = BAD_HEIGHTMAPS[case]
    write_heightmap(tmp_path / "good.png", np.random.default_rng(1).uniform(size=(64, 64)))
    folder = tmp_path / "scene"
    folder.mkdir()
    heightmap = make(folder)
    scene_file = folder / "scene.toml"
    scene_file.write_text(f'[terrain]\nkind = "heightmap"\nheightmap = {heightmap!r}\nheight = 100.0\n')
    with pytest.raises(SceneError) as refused:
        load_scene(scene_file)
    message = str(refused.value)
    assert message.startswith(f"{scene_file}: terrain.heightmap: ") and problem in message and "\n" not in message
    assert main(["export", str(scene_file), "--out", str(tmp_path / "path.csv")]) == 2
    assert capsys.readouterr().err == f"cloudview: error: {message}\n"
    assert not (tmp_path / "path.csv").exists()


BAD_TERRAIN_KEYS = {
    "resolution": ({"resolution": 64}, "terrain.resolution: a heightmap's pixels are its samples"),
    "NaN height": ({"height": float("nan")}, "terrain.height: "),
    "ramp out of order": (
        {"color_ramp": [[100.0, 0.1, 0.1, 0.1], [50.0, 0.2, 0.2, 0.2]]},
        "terrain.color_ramp: the rows' heights must increase strictly",
    ),
    "ramp colour": ({"color_ramp": [[0.0, 2.0, 0.1, 0.1]]}, "terrain.color_ramp: colours must be within [0, 1]"),
    "slopes reversed": ({"steep_slope_deg": [40.0, 20.0]}, "terrain.steep_slope_deg: expected [from, to]"),
}


@pytest.mark.parametrize("case", BAD_TERRAIN_KEYS)
def test_bad_heightmap_keys_are_refused(tmp_path, case):
    keys, problem = BAD_TERRAIN_KEYS[case]
    with pytest.raises(SceneError, match=problem.replace("[", r"\[").replace("(", r"\(").replace(")", r"\)")):
        scene_from_dict(heightmap_scene(tmp_path, np.zeros((4, 4)), **keys), "s.toml", tmp_path)


def test_a_heightmap_key_on_a_procedural_terrain_is_refused(tmp_path):
    data = heightmap_scene(tmp_path, np.zeros((4, 4)))
    data["terrain"]["kind"] = "heightfield"
    with pytest.raises(SceneError, match="terrain.heightmap: only a terrain of kind 'heightmap' reads it"):
        scene_from_dict(data, "s.toml", tmp_path)


def test_heights_compare_and_hash_by_value():
    a, b = HeightGrid(np.eye(3)), HeightGrid(np.eye(3))
    assert a == b and hash(a) == hash(b) and HeightGrid(np.zeros((3, 3))) != a
    with pytest.raises(ValueError, match="at least 2x2"):
        HeightGrid(np.zeros((1, 5)))


@pytest.mark.gl
def test_the_heightmap_valley_renders_as_the_procedural_one(renderer):
    """The example's terrain, its colours plain, drawn through the same tiles, light and shadows as the procedural
    valley it was sampled from: near the same picture (the image holds the patch alone; past it the valley's
    noise goes on and the image's edge is held)."""
    heightmap = load_scene(EXAMPLE)
    plain = dataclasses.replace(heightmap.terrain, color_ramp=(), steep_color=None)
    procedural = dataclasses.replace(load_scene(DEFAULT_SCENE).terrain)
    pictures = [
        renderer.render(dataclasses.replace(heightmap, terrain=terrain))[0].astype(np.float64)
        for terrain in (plain, procedural)
    ]
    psnr = 10.0 * np.log10(255.0**2 / np.mean((pictures[0] - pictures[1]) ** 2))
    assert psnr > 32.0
    coloured = renderer.render(heightmap)[0].astype(np.float64)
    assert np.abs(coloured - pictures[0]).max() > 20.0  # the ramp and the steep colour show


def test_an_edit_that_leaves_the_terrain_alone_does_not_check_its_heights_again(monkeypatch):
    """The editor checks every edit's limits: a 4097^2 heightmap's samples took 0.29 s each time."""
    from cloudcore.model.scene import Scene
    from cloudcore.scenes import limits

    scene = Scene(terrain=Terrain(kind="heightmap", heightmap="h.png", heights=HeightGrid(np.zeros((3, 3)))))
    looked_at = []
    real = limits._out_of_bounds
    monkeypatch.setattr(limits, "_out_of_bounds", lambda field, *rest: looked_at.append(field) or real(field, *rest))
    edited = dataclasses.replace(scene, description="moved a cloud")
    assert limits.scene_limit_problems(edited, unchanged=scene) == [] and "terrain" not in looked_at
    broken = dataclasses.replace(scene.terrain, heights=HeightGrid(np.full((3, 3), np.nan)))
    problems = limits.scene_limit_problems(dataclasses.replace(scene, terrain=broken), unchanged=scene)
    assert problems == [("terrain.heightmap.values", "numbers must be finite, got nan")]


def test_a_geotiff_s_elevations_are_read_whole_with_the_extent_and_rise_it_gives(tmp_path):
    """Float32 elevations in metres over a projected model's 30 m pixels: the lowest becomes the ground's 0, the
    terrain rises by the file's span, over the extent its pixel scale gives, unless the scene says otherwise."""
    elevations = 1200.0 + 800.0 * np.random.default_rng(4).random((40, 60))
    (tmp_path / "dem.tif").write_bytes(geotiff_bytes(elevations, (30.0, 30.0), PROJECTED_IN_METRES, (5e5, 4.1e6)))
    terrain = scene_from_dict({"terrain": {"kind": "heightmap", "heightmap": "dem.tif"}}, base_dir=tmp_path).terrain
    assert terrain.size == (60 * 30.0, 40 * 30.0)
    rise = float(np.ptp(elevations.astype(np.float32)))
    assert terrain.height == pytest.approx(rise)
    np.testing.assert_allclose(
        terrain.heights.values * terrain.height,
        elevations.astype(np.float32) - elevations.astype(np.float32).min(),
        atol=1e-9 * rise,
    )
    given = {"kind": "heightmap", "heightmap": "dem.tif", "size": [900.0, 400.0], "height": 50.0}
    assert scene_from_dict({"terrain": given}, base_dir=tmp_path).terrain.size == (900.0, 400.0)
    saved = tmp_path / "scene.toml"
    save_scene(scene_from_dict({"terrain": given}, base_dir=tmp_path), saved)
    again = load_scene(saved).terrain
    assert again.heightmap == "dem.tif" and again.heights == HeightGrid(terrain.heights.values)


def test_a_geographic_geotiff_s_degrees_become_metres_at_its_middle_latitude(tmp_path):
    """One arc-second pixels (SRTM's) at 46 degrees north: a degree of longitude spans cos(46) of the equator's."""
    elevations = np.linspace(300.0, 2900.0, 3600).reshape(60, 60)
    second = 1.0 / 3600.0
    (tmp_path / "srtm.tif").write_bytes(
        geotiff_bytes(elevations, (second, second), GEOGRAPHIC, (7.0, 46.0 + 30 * second))
    )
    terrain = scene_from_dict({"terrain": {"kind": "heightmap", "heightmap": "srtm.tif"}}, base_dir=tmp_path).terrain
    across, down = terrain.size
    assert across == pytest.approx(60 * second * 111_320.0 * np.cos(np.radians(46.0)), rel=1e-9)
    assert down == pytest.approx(60 * second * 110_574.0, rel=1e-9)
    ungeoreferenced = tmp_path / "plain.tif"
    ungeoreferenced.write_bytes(geotiff_bytes(elevations))
    plain = scene_from_dict({"terrain": {"kind": "heightmap", "heightmap": "plain.tif"}}, base_dir=tmp_path).terrain
    assert plain.size == Terrain().size and plain.height == pytest.approx(2600.0)  # the default extent, its rise
