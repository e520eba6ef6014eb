"""Scene files: TOML in, TOML out, nothing half-loaded, saves atomic.

The format is documented in docs/scene-format.md.  Every problem is a
`SceneError` naming the file, the field (as a dotted path such as
`clouds[3].particles`) and what is wrong; unknown keys are refused with the
valid ones listed, so a typo never passes silently.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import tomlkit

from cloudcore.artist.cloudgen import PRESETS
from cloudcore.light.lighting import SKIES
from cloudcore.light.phase import PHASE_NAMES
from cloudcore.light.shading import EYE_PASSES, LIGHT_PASSES
from cloudcore.model.cloud_records import FACINGS, FORMATION_KINDS, MAX_SEED, ArtistShading, Formation, SpriteStyle
from cloudcore.model.errors import SceneError
from cloudcore.model.particle_files import (
    atomic_write,
    open_particle_array,
    remove_unnamed_particle_files,
    store_particles,
)
from cloudcore.model.scene import (
    DEFAULT_VIEW_NAME,
    MAX_LAYERS,
    MAX_RINGS,
    Air,
    Camera,
    CameraPath,
    Cloud,
    CloudField,
    HeightGrid,
    Light,
    Lighting,
    Scene,
    SceneObject,
    Shading,
    Terrain,
    View,
    Weather,
    Wind,
)
from cloudcore.model.settings import AUTO_SCALE, MODES, RenderSettings, setting_options
from cloudcore.model.toml_table import Table, checked_matrix, field_error, read_toml
from cloudcore.scenes.interop.heightmap import Heightmap, read_heightmap_file, store_heightmap
from cloudcore.scenes.limits import FIELD_RANGES, camera_path_keys_problem, scene_limit_problems

PRIMITIVES = ("box", "sphere", "aircraft")
#: a terrain's side in metres, at least: its noise is scaled to the side, and a side of 5e-324 m halved to 0
#: and put NaN in the heights
MIN_TERRAIN_SIDE_M = 1.0
TERRAIN_KINDS = ("heightfield", "heightmap", "mesh")
#: TOML arrays are slow to parse; clouds larger than this are saved to .npy.
INLINE_PARTICLE_LIMIT = 64


def record_keys(record, *, leave_out: tuple[str, ...] = ()) -> tuple[str, ...]:
    """A table's keys: the record's fields in their order, less those a file does not hold."""
    return tuple(f.name for f in dataclasses.fields(record) if f.name not in leave_out)


#: every table of a scene file (dotted as in TOML; "" the top level) and its keys, from the records
#: they are read into, so a new field is a new key; docs/scene-format.md names each (a test checks)
TABLE_KEYS = {
    "": record_keys(Scene),
    "camera": record_keys(Camera),
    "lighting": record_keys(Lighting),
    "lighting.lights": record_keys(Light),
    "lighting.air": record_keys(Air),
    "shading": record_keys(Shading),
    "clouds": record_keys(Cloud),
    "clouds.formation": record_keys(Formation),
    "clouds.sprite": record_keys(SpriteStyle),
    "clouds.artist": record_keys(ArtistShading),
    "cloud_field": record_keys(CloudField),
    "wind": record_keys(Wind),
    "weather": record_keys(Weather),
    # a heightmap's heights are read from `heightmap`, not written in the scene
    "terrain": record_keys(Terrain, leave_out=("heights",)),
    # a mesh file's triangles are read from `mesh`, not written in the scene
    "objects": record_keys(SceneObject, leave_out=("vertices", "faces")),
    "camera_paths": record_keys(CameraPath),
    "views": record_keys(View),
}


def load_scene(path) -> Scene:
    """Read and validate a scene file; raise SceneError on any problem."""
    path = Path(path)
    return scene_from_dict(read_toml(path), str(path), path.parent)


def scene_from_dict(data: dict, source: str = "<scene>", base_dir=Path(".")) -> Scene:
    root = Table(source, "", data)
    root.reject_unknown(TABLE_KEYS[""])
    clouds = tuple(_cloud(t, Path(base_dir)) for t in root.tables("clouds"))
    _unique_names(root, "clouds", clouds)
    objects = tuple(_object(t, Path(base_dir)) for t in root.tables("objects"))
    _unique_names(root, "objects", objects)
    paths = tuple(_camera_path(t) for t in root.tables("camera_paths"))
    _unique_names(root, "camera_paths", paths)
    camera = _camera(Table(source, "camera", root.raw("camera", {})))
    views = tuple(_view(t, camera, paths) for t in root.tables("views"))
    _unique_names(root, "views", views)
    scene = Scene(
        camera=camera,
        lighting=_lighting(Table(source, "lighting", root.raw("lighting", {}))),
        shading=_shading(Table(source, "shading", root.raw("shading", {}))),
        clouds=clouds,
        terrain=_terrain(Table(source, "terrain", root.raw("terrain")), Path(base_dir))
        if root.has("terrain")
        else None,
        objects=objects,
        camera_paths=paths,
        description=root.string("description", ""),
        views=views,
        cloud_field=root.table("cloud_field", _cloud_field),
        wind=root.table("wind", read_wind),
        weather=root.table("weather", _weather),
    )
    # what every field allows, the renderer may still not draw: refuse that here, not in the GL code
    problems = scene_limit_problems(scene)
    if problems:
        raise field_error(source, *problems[0])
    return scene


def _range(record, key: str) -> dict:
    """The `low` and `high` keyword arguments of a Table read for the record's field (`FIELD_RANGES`)."""
    low, high = FIELD_RANGES[(record, key)]
    return {"low": low, "high": high}


def _unique_names(root: Table, key: str, items) -> None:
    seen = set()
    for i, item in enumerate(items):
        if item.name in seen:
            raise field_error(root.source, f"{key}[{i}].name", f"duplicate name {item.name!r}")
        seen.add(item.name)


def _view(t: Table, camera: Camera, paths: tuple[CameraPath, ...]) -> View:
    """One `[[views]]` table; what it leaves out of the camera is `camera`'s (the scene's)."""
    t.reject_unknown(TABLE_KEYS["views"])
    name = t.string("name")
    if name == DEFAULT_VIEW_NAME:
        t.fail("name", f"{DEFAULT_VIEW_NAME!r} is the scene's [camera]; give this view another name")
    # the name is a file name too: the golden is <goldens>/<scene>/<view>.png
    if not name or name.startswith(".") or not all(ch.isalnum() or ch in "-_." for ch in name):
        t.fail("name", f"{name!r} must be letters, digits, '-', '_' or '.' (not first), to name a golden file")
    position = t.vector("position", None) if t.has("position") else None
    look_at = t.vector("look_at", None) if t.has("look_at") else None
    camera_path = t.string("camera_path") if t.has("camera_path") else None
    t_s = 0.0
    if camera_path is not None:
        if position is not None or look_at is not None:
            t.fail("camera_path", "give either position and look_at, or camera_path and t, not both")
        path = next((p for p in paths if p.name == camera_path), None)
        if path is None:
            known = ", ".join(p.name for p in paths) or "none"
            t.fail("camera_path", f"no camera path named {camera_path!r}; the scene has: {known}")
        t_s = t.number("t", 0.0, low=0.0, high=path.duration)
    elif t.has("t"):
        t.fail("t", "t is seconds along camera_path, and this view has none")
    elif np.allclose(position or camera.position, look_at or camera.look_at, rtol=0, atol=0):
        if look_at is not None:
            t.fail("look_at", "must differ from position")
        t.fail("position", "must differ from look_at (the scene camera's)")
    mode = t.string("mode", "full", choices=MODES)
    settings = t.table("settings", settings_overrides) or ()
    try:
        RenderSettings(mode=mode, **dict(settings))
    except ValueError as error:
        t.fail("settings", str(error))
    return View(
        name=name,
        position=position,
        look_at=look_at,
        fov_y_deg=t.number("fov_y_deg", None, **_range(View, "fov_y_deg")) if t.has("fov_y_deg") else None,
        camera_path=camera_path,
        t=t_s,
        time_of_day=t.number("time_of_day", None, **_range(View, "time_of_day")) if t.has("time_of_day") else None,
        time_s=t.number("time_s", 0.0),
        mode=mode,
        settings=settings,
        tolerance_psnr=t.number("tolerance_psnr", None, **_range(View, "tolerance_psnr"))
        if t.has("tolerance_psnr")
        else None,
        max_diff=t.integer("max_diff", None, low=0, high=255) if t.has("max_diff") else None,
    )


#: what a view's [views.settings] may set: every RenderSettings field but `mode` (a key of the view itself)
VIEW_SETTINGS = tuple(f.name for f in dataclasses.fields(RenderSettings) if f.name != "mode")


def settings_overrides(t: Table) -> tuple[tuple[str, object], ...]:
    """RenderSettings overrides, each of its field's type; their ranges are RenderSettings' own (checked by the
    caller, with the view's mode)."""
    t.reject_unknown(VIEW_SETTINGS)
    defaults = RenderSettings()
    values = []
    for key in t.data:
        default = getattr(defaults, key)
        if isinstance(default, bool):
            value = t.boolean(key)
        elif isinstance(default, int):
            value = t.integer(key, None, low=0, high=2**31 - 1)
        elif isinstance(default, str):
            value = t.string(key, choices=setting_options()[key].choices)
        elif key == "ring_radius" and t.raw(key) == math.inf:  # inf: no ring, as on the command line
            value = math.inf
        elif key == "cloud_resolution_scale" and t.raw(key) == AUTO_SCALE:  # chosen per frame, as on the command line
            value = AUTO_SCALE
        else:
            value = t.number(key)
        values.append((key, value))
    return tuple(values)


def _camera(t: Table) -> Camera:
    t.reject_unknown(TABLE_KEYS["camera"])
    default = Camera()
    position = t.vector("position", default.position)
    look_at = t.vector("look_at", default.look_at)
    if np.allclose(position, look_at, rtol=0, atol=0):
        t.fail("look_at", "must differ from position")
    return Camera(position, look_at, t.number("fov_y_deg", default.fov_y_deg, **_range(Camera, "fov_y_deg")))


def _lighting(t: Table) -> Lighting:
    t.reject_unknown(TABLE_KEYS["lighting"])
    lights = []
    for lt in t.tables("lights"):
        lt.reject_unknown(TABLE_KEYS["lighting.lights"])
        lights.append(
            Light(
                lt.vector("direction", unit=True),
                lt.vector("color", (1.0, 1.0, 1.0), **_range(Light, "color")),
                lt.number("intensity", 1.0, **_range(Light, "intensity")),
            )
        )
    # Explicit lights replace the sun and skylight; a time of day still sets the sky.
    if t.has("time_of_day"):
        time_of_day = t.number("time_of_day", **_range(Lighting, "time_of_day"))
    else:
        time_of_day = None if lights else Lighting().time_of_day
    ambient = t.vector("ambient", None, **_range(Lighting, "ambient")) if t.has("ambient") else None
    return Lighting(time_of_day, tuple(lights), ambient, t.table("air", _air) or Air())


def _air(t: Table) -> Air:
    t.reject_unknown(TABLE_KEYS["lighting.air"])
    d = Air()
    return Air(
        sky=t.string("sky", d.sky, choices=SKIES),
        mie_density_scale=t.number("mie_density_scale", d.mie_density_scale, **_range(Air, "mie_density_scale")),
        ground_albedo=t.number("ground_albedo", d.ground_albedo, **_range(Air, "ground_albedo")),
        origin_altitude_m=t.number("origin_altitude_m", d.origin_altitude_m, **_range(Air, "origin_altitude_m")),
    )


def _shading(t: Table) -> Shading:
    t.reject_unknown(TABLE_KEYS["shading"])
    d = Shading()
    return Shading(
        albedo=t.number("albedo", d.albedo, **_range(Shading, "albedo")),
        optical_depth=t.number("optical_depth", d.optical_depth, **_range(Shading, "optical_depth")),
        phase=t.string("phase", d.phase, choices=PHASE_NAMES),
        g=t.number("g", d.g, **_range(Shading, "g")),
        eye_pass=t.string("eye_pass", d.eye_pass, choices=EYE_PASSES),
        light_pass=t.string("light_pass", d.light_pass, choices=LIGHT_PASSES),
        ground_bounce=t.boolean("ground_bounce", d.ground_bounce),
    )


def _cloud(t: Table, base_dir: Path) -> Cloud:
    t.reject_unknown(TABLE_KEYS["clouds"])
    name = t.string("name")
    if t.has("particles") == t.has("particles_file"):
        t.fail("particles", "give exactly one of particles (inline) or particles_file (.npy)")
    if t.has("particles"):
        particles, particles_file = t.matrix("particles", 4, allow_empty=True), None
    else:
        particles_file = t.string("particles_file")
        particles = _read_particles(t, base_dir / particles_file)
    return Cloud(
        name=name,
        particles=particles,
        particles_file=particles_file,
        optical_depth=t.number("optical_depth", None, **_range(Cloud, "optical_depth"))
        if t.has("optical_depth")
        else None,
        albedo=t.number("albedo", None, **_range(Cloud, "albedo")) if t.has("albedo") else None,
        color=t.vector("color", (1.0, 1.0, 1.0), **_range(Cloud, "color")),
        formation=t.table("formation", _formation),
        sprite=t.table("sprite", _sprite),
        artist=t.table("artist", _artist),
        shading_group_size=t.number("shading_group_size", None, low=0.0, low_open=True)
        if t.has("shading_group_size")
        else None,
    )


def _cloud_field(t: Table) -> CloudField:
    """`[cloud_field]`: types here, ranges by the record itself (the editor's panel edits it too)."""
    t.reject_unknown(TABLE_KEYS["cloud_field"])
    d = CloudField()
    return t.record(
        CloudField,
        seed=t.integer("seed", d.seed, low=0, high=2**31 - 1),
        coverage=t.number("coverage", d.coverage),
        cell_size=t.number("cell_size", d.cell_size),
        rings=t.integer("rings", d.rings, low=1, high=MAX_RINGS),
        layers=t.integer("layers", d.layers, low=1, high=MAX_LAYERS),
        altitude=t.row("altitude", 2, d.altitude),
        cloud_type=t.string("cloud_type", d.cloud_type, choices=tuple(PRESETS)),
        extent=t.row("extent", 2, d.extent),
        centre=t.row("centre", 2, d.centre),
    )


def read_wind(t: Table) -> Wind:
    """`[wind]`: types here, ranges by the record itself (the editor's panel edits it too)."""
    t.reject_unknown(TABLE_KEYS["wind"])
    d = Wind()
    return t.record(
        Wind,
        bands=tuple(map(tuple, t.matrix("bands", 3))) if t.has("bands") else d.bands,
        **{name: t.number(name, getattr(d, name)) for name in record_keys(Wind, leave_out=("bands",))},
    )


def _weather(t: Table) -> Weather:
    """`[weather]`: types here, names and ranges by the record itself (the editor's combo sets it too)."""
    t.reject_unknown(TABLE_KEYS["weather"])
    d = Weather()
    return t.record(
        Weather,
        preset=t.string("preset", d.preset),
        to=t.string("to") if t.has("to") else None,
        start_s=t.number("start_s", d.start_s),
        duration_s=t.number("duration_s", d.duration_s),
    )


def _formation(t: Table) -> Formation:
    t.reject_unknown(TABLE_KEYS["clouds.formation"])
    return Formation(
        kind=t.string("kind", choices=FORMATION_KINDS),
        start_s=t.number("start_s", 0.0),
        duration_s=t.number("duration_s", low=0.0),
    )


def _sprite(t: Table) -> SpriteStyle:
    t.reject_unknown(TABLE_KEYS["clouds.sprite"])
    d = SpriteStyle()
    return t.record(
        SpriteStyle,
        rows=t.integers("rows", d.rows),
        rotation_deg=t.row("rotation_deg", 2, d.rotation_deg),
        facing=t.string("facing", d.facing, choices=FACINGS),
        seed=t.integer("seed", d.seed, low=0, high=MAX_SEED),
        flat_bottom_fraction=t.number("flat_bottom_fraction", d.flat_bottom_fraction),
        flat_bottom_rotation_deg=t.row("flat_bottom_rotation_deg", 2, d.flat_bottom_rotation_deg),
    )


def _artist(t: Table) -> ArtistShading:
    t.reject_unknown(TABLE_KEYS["clouds.artist"])
    d = ArtistShading()

    def keys(key: str, columns: int):
        return t.matrix(key, columns) if t.has(key) else getattr(d, key)

    return t.record(
        ArtistShading,
        levels=keys("levels", 5),
        level_percent_by_hour=keys("level_percent_by_hour", 2),
        directional_colour_by_hour=keys("directional_colour_by_hour", 4),
        directional_range=t.row("directional_range", 3, d.directional_range),
    )


def _check_regular_file(t: Table, key: str, file: Path) -> None:
    """`file` is a file to read: not missing, not a folder, and not a pipe or device (a FIFO blocked the load
    forever)."""
    if not file.exists():
        t.fail(key, f"{file}: no such file")
    if file.is_dir():
        t.fail(key, f"{file}: is a folder, not a file")
    if not file.is_file():
        t.fail(key, f"{file}: not a regular file (a pipe or a device)")


def _read_particles(t: Table, file: Path) -> np.ndarray:
    _check_regular_file(t, "particles_file", file)
    try:
        array = open_particle_array(file)  # memory-mapped: checked_matrix copies the data out of the map
    except FileNotFoundError:  # removed since it was looked at
        t.fail("particles_file", f"{file}: no such file")
    except Exception as error:  # a forged header raises ValueError, OverflowError, TokenError, BadZipFile...
        t.fail("particles_file", f"{file}: not a readable .npy ({error})")
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "fiu":
        t.fail("particles_file", f"{file}: expected a numeric array")
    return checked_matrix(array, 4, t.source, t.path("particles_file"), True)


def _terrain(t: Table, base_dir: Path) -> Terrain:
    t.reject_unknown(TABLE_KEYS["terrain"])
    d = Terrain()
    kind = t.string("kind", d.kind, choices=TERRAIN_KINDS)
    if kind != "heightmap" and t.has("heightmap"):
        t.fail("heightmap", f"only a terrain of kind 'heightmap' reads it, this one is {kind!r}")
    if kind == "heightmap" and t.has("resolution"):
        t.fail("resolution", "a heightmap's pixels are its samples: leave resolution out")
    heightmap = t.string("heightmap") if kind == "heightmap" else None
    read = _read_heightmap(t, base_dir, heightmap) if heightmap is not None else None
    # a georeferenced elevation model gives the extent and the height it spans where the scene leaves them out
    size = t.raw("size", list(read.extent_m if read is not None and read.extent_m is not None else d.size))
    if not (isinstance(size, list) and len(size) == 2):
        t.fail("size", f"expected [size_x, size_z] in metres, got {size!r}")
    sx = Table(t.source, t.path("size"), {"x": size[0], "z": size[1]})
    height = read.rise_m if read is not None and read.rise_m is not None else d.height
    return Terrain(
        kind=kind,
        size=(sx.number("x", low=MIN_TERRAIN_SIDE_M), sx.number("z", low=MIN_TERRAIN_SIDE_M)),
        resolution=t.integer("resolution", d.resolution, low=2, high=4096),
        height=t.number("height", height, **_range(Terrain, "height")),
        seed=t.integer("seed", d.seed, low=0, high=2**31 - 1),
        mesh=t.string("mesh") if kind == "mesh" else None,
        color=t.vector("color", d.color, **_range(Terrain, "color")),
        relief=t.number("relief", d.relief, **_range(Terrain, "relief")),
        reach=t.number("reach", d.reach, **_range(Terrain, "reach")),
        heightmap=heightmap,
        heights=HeightGrid(read.heights) if read is not None else None,
        color_ramp=tuple(map(tuple, t.matrix("color_ramp", 4).tolist())) if t.has("color_ramp") else (),
        steep_color=t.vector("steep_color", None, **_range(Terrain, "steep_color")) if t.has("steep_color") else None,
        steep_slope_deg=t.row("steep_slope_deg", 2, d.steep_slope_deg),
    )


def _read_heightmap(t: Table, base_dir: Path, heightmap: str) -> Heightmap:
    """The PNG or GeoTIFF `heightmap` names, a path relative to the scene's folder that stays inside it (a scene
    passed on may read no other file of its reader's)."""
    if Path(heightmap).is_absolute():
        t.fail("heightmap", f"{heightmap!r}: must be relative to the scene file's folder, not absolute")
    folder = base_dir.resolve()
    file = (folder / heightmap).resolve()
    if not file.is_relative_to(folder):
        t.fail("heightmap", f"{heightmap!r}: leads outside the scene file's folder ({folder})")
    try:
        return read_heightmap_file(file)
    except SceneError as error:
        t.fail("heightmap", f"{error.source}: {error.problem}")


def _object(t: Table, base_dir: Path) -> SceneObject:
    t.reject_unknown(TABLE_KEYS["objects"])
    if t.has("mesh") == t.has("primitive"):
        t.fail("mesh", "give exactly one of mesh (a file) or primitive")
    path = None
    if t.has("path"):
        path = t.matrix("path", 4)
        _check_times(t, "path", path[:, 0])
    mesh = t.string("mesh") if t.has("mesh") else None
    vertices, faces = _read_mesh(t, base_dir / mesh) if mesh is not None else (None, None)
    return SceneObject(
        name=t.string("name"),
        mesh=mesh,
        vertices=vertices,
        faces=faces,
        primitive=t.string("primitive", choices=PRIMITIVES) if t.has("primitive") else None,
        scale=t.number("scale", 1.0, low=0.0, low_open=True),
        position=t.vector("position", (0.0, 0.0, 0.0)),
        path=path,
        color=t.vector("color", SceneObject("").color, **_range(SceneObject, "color")),
    )


def _read_mesh(t: Table, file: Path) -> tuple[np.ndarray, np.ndarray]:
    """The triangles of a mesh file trimesh reads (all its geometry merged), checked finite."""
    import trimesh

    _check_regular_file(t, "mesh", file)
    try:
        mesh = trimesh.load(file, force="mesh")
    except Exception as error:  # trimesh raises many kinds on a file it cannot parse
        t.fail("mesh", f"{file}: not a mesh trimesh can read ({error})")
    vertices, faces = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
    if len(faces) == 0:
        t.fail("mesh", f"{file}: no triangles")
    if not np.all(np.isfinite(vertices)):
        t.fail("mesh", f"{file}: vertices must be finite")
    return vertices, faces


def _camera_path(t: Table) -> CameraPath:
    t.reject_unknown(TABLE_KEYS["camera_paths"])
    keys = t.matrix("keys", 7)
    problem = camera_path_keys_problem(keys)
    if problem is not None:
        t.fail("keys", problem)
    return CameraPath(t.string("name"), keys)


def _check_times(t: Table, key: str, times: np.ndarray) -> None:
    if np.any(np.diff(times) <= 0):
        t.fail(key, "key times must increase strictly")


# ---------------------------------------------------------------- saving


def scene_to_dict(scene: Scene) -> dict:
    """The TOML document for `scene` (particles of clouds with a particles_file are not inlined)."""
    c, s = scene.camera, scene.shading
    data: dict = {}
    if scene.description:
        data["description"] = scene.description
    data["camera"] = {"position": list(c.position), "look_at": list(c.look_at), "fov_y_deg": c.fov_y_deg}
    lighting: dict = {}
    if scene.lighting.time_of_day is not None:
        lighting["time_of_day"] = scene.lighting.time_of_day
    if scene.lighting.ambient is not None:
        lighting["ambient"] = list(scene.lighting.ambient)
    if scene.lighting.lights:
        lighting["lights"] = [
            {"direction": list(light.direction), "color": list(light.color), "intensity": light.intensity}
            for light in scene.lighting.lights
        ]
    if scene.lighting.air != Air():
        lighting["air"] = dataclasses.asdict(scene.lighting.air)
    data["lighting"] = lighting
    data["shading"] = {"albedo": s.albedo, "optical_depth": s.optical_depth, "phase": s.phase, "g": s.g}
    for key in ("eye_pass", "light_pass", "ground_bounce"):  # files that keep Harris's model stay as they were
        if getattr(s, key) != getattr(Shading(), key):
            data["shading"][key] = getattr(s, key)
    if scene.terrain is not None:
        t = scene.terrain
        terrain = {"kind": t.kind, "size": list(t.size), "resolution": t.resolution, "height": t.height, "seed": t.seed}
        if t.kind == "heightmap":  # its pixels are its samples; the seed stays, the mountains' of `relief`
            del terrain["resolution"]
            terrain["heightmap"] = t.heightmap
        terrain["color"] = list(t.color)
        for key in ("relief", "reach"):  # files without them stay as they were
            if getattr(t, key) != getattr(Terrain(), key):
                terrain[key] = getattr(t, key)
        if t.mesh is not None:
            terrain["mesh"] = t.mesh
        if t.color_ramp:
            terrain["color_ramp"] = _rows(np.array(t.color_ramp))
        if t.steep_color is not None:
            terrain.update(steep_color=list(t.steep_color), steep_slope_deg=list(t.steep_slope_deg))
        data["terrain"] = terrain
    data["clouds"] = [_cloud_dict(cloud) for cloud in scene.clouds]
    if scene.cloud_field is not None:
        data["cloud_field"] = _record_dict(scene.cloud_field)
    if scene.wind is not None:
        data["wind"] = _record_dict(scene.wind)
    if scene.weather is not None:
        data["weather"] = {k: v for k, v in _record_dict(scene.weather).items() if v is not None}
    data["objects"] = [_object_dict(o) for o in scene.objects]
    data["camera_paths"] = [{"name": p.name, "keys": _rows(p.keys)} for p in scene.camera_paths]
    data["views"] = [_view_dict(view) for view in scene.views]
    return {k: v for k, v in data.items() if v != []}


def _view_dict(view: View) -> dict:
    """A view's table: only what it sets (left out, the scene's camera and the defaults apply)."""
    out: dict = {"name": view.name}
    for key in ("position", "look_at"):
        if getattr(view, key) is not None:
            out[key] = list(getattr(view, key))
    for key in ("fov_y_deg", "camera_path"):
        if getattr(view, key) is not None:
            out[key] = getattr(view, key)
    if view.camera_path is not None:
        out["t"] = view.t
    if view.time_of_day is not None:
        out["time_of_day"] = view.time_of_day
    if view.time_s:
        out["time_s"] = view.time_s
    out["mode"] = view.mode
    if view.settings:
        out["settings"] = dict(view.settings)
    for key in ("tolerance_psnr", "max_diff"):
        if getattr(view, key) is not None:
            out[key] = getattr(view, key)
    return out


def _cloud_dict(cloud: Cloud) -> dict:
    out: dict = {"name": cloud.name}
    if cloud.particles_file is not None:
        out["particles_file"] = cloud.particles_file
    else:
        out["particles"] = _rows(cloud.particles)
    for key in ("optical_depth", "albedo"):
        if getattr(cloud, key) is not None:
            out[key] = getattr(cloud, key)
    out["color"] = list(cloud.color)
    if cloud.shading_group_size is not None:
        out["shading_group_size"] = cloud.shading_group_size
    for key in ("formation", "sprite", "artist"):
        if getattr(cloud, key) is not None:
            out[key] = _record_dict(getattr(cloud, key))
    return out


def _record_dict(record) -> dict:
    """A frozen record's fields as a TOML table: tables of rows one row per line, tuples as arrays."""
    out = {}
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if isinstance(value, tuple) and value and isinstance(value[0], tuple):
            value = _rows(np.array(value))
        elif isinstance(value, tuple):
            value = list(value)
        out[f.name] = value
    return out


def _object_dict(o: SceneObject) -> dict:
    out: dict = {"name": o.name}
    out["mesh" if o.mesh is not None else "primitive"] = o.mesh if o.mesh is not None else o.primitive
    out.update(scale=o.scale, position=list(o.position), color=list(o.color))
    if o.path is not None:
        out["path"] = _rows(o.path)
    return out


def _rows(matrix: np.ndarray):
    """A matrix as a TOML array with one row per line, the way people read it."""
    array = tomlkit.array()
    array.extend(matrix.tolist())
    return array.multiline(True)


def save_scene(scene: Scene, path) -> Scene:
    """Write `scene` to `path` atomically, particle files included; return the scene as saved.

    Clouds with more than INLINE_PARTICLE_LIMIT particles or with a particles_file
    are stored as .npy (`cloudcore.model.particle_files.store_particles`).  No existing particle file is ever
    overwritten with other particles, so until the TOML is replaced, in one rename
    that commits the save, the previous TOML and every file it names are intact: a
    crash at any moment leaves the old scene or the new one, never a mix.  After
    the commit, particle files in the scene's own folder the new TOML does not
    name are deleted.  A heightmap terrain's image is written beside the scene where
    the folder lacks it (`cloudcore.scenes.interop.heightmap.store_heightmap`), on the same rule.
    """
    path = Path(path)
    saved_clouds = tuple(
        dataclasses.replace(cloud, particles_file=store_particles(cloud, path))
        if cloud.particles_file is not None or len(cloud.particles) > INLINE_PARTICLE_LIMIT
        else cloud
        for cloud in scene.clouds
    )
    terrain = scene.terrain
    if terrain is not None and terrain.heights is not None:
        stored = store_heightmap(terrain.heights.values, terrain.heightmap or "", path)
        terrain = dataclasses.replace(terrain, heightmap=stored)
    saved = dataclasses.replace(scene, clouds=saved_clouds, terrain=terrain)
    document = tomlkit.dumps(scene_to_dict(saved)).encode("utf-8")
    atomic_write(path, lambda f: f.write(document))
    remove_unnamed_particle_files(path, {c.particles_file for c in saved_clouds if c.particles_file is not None})
    return saved
