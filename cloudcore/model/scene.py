"""The scene model: immutable records with numpy arrays, float64.

Edits make new records (`dataclasses.replace`), which keeps undo cheap and lets
the renderer compare identities to see what changed.  Validation happens where
input enters (`cloudcore.scenes.files`); these types only normalise.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from dataclasses import dataclass, field

import numpy as np

from cloudcore.model.cloud_records import ArtistShading, Formation, SpriteStyle
from cloudcore.model.errors import FieldError

Vec3 = tuple[float, float, float]


def _frozen_array(value, columns: int) -> np.ndarray:
    array = np.array(value, dtype=np.float64).reshape(-1, columns)
    array.flags.writeable = False
    return array


class _Record:
    """Equality field by field, with numpy arrays compared by value."""

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        for f in dataclasses.fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                if a is None or b is None or not np.array_equal(a, b):
                    return False
            elif a != b:
                return False
        return True

    # value equality over arrays has no matching cheap hash; records are compared, never hashed
    __hash__ = None


@dataclass(frozen=True)
class Camera:
    position: Vec3 = (0.0, 500.0, 3000.0)
    look_at: Vec3 = (0.0, 700.0, 0.0)
    fov_y_deg: float = 60.0


@dataclass(frozen=True)
class Light:
    """A directional light; `direction` points from the scene toward the light (unit)."""

    direction: Vec3
    color: Vec3 = (1.0, 1.0, 1.0)
    intensity: float = 1.0


@dataclass(frozen=True)
class Air:
    """The air over a scene (docs/atmosphere.md): `sky` "physical" takes the sky and the sun's and the sky's
    light from Hillaire's atmosphere (`cloudcore.atmosphere`), "gradient" the two-colour sky and the
    heuristic light of before (older pictures made again); the aerosols' density as a multiple of Earth's
    clear air, the ground's albedo, and the altitude of the scene's origin above sea level."""

    sky: str = "physical"
    mie_density_scale: float = 1.0
    ground_albedo: float = 0.3
    origin_altitude_m: float = 0.0


@dataclass(frozen=True)
class Lighting:
    """Either a time of day (sun, skylight and ambient follow) or explicit lights; the air the sky and the
    sun's light come through."""

    time_of_day: float | None = 15.5
    lights: tuple[Light, ...] = ()
    ambient: Vec3 | None = None
    air: Air = Air()


@dataclass(frozen=True)
class Shading:
    """Harris's defaults for every cloud; `eye_pass` chooses what a particle sends to the eye
    (`cloudcore.light.shading.EYE_PASSES`: Harris's eq. 5, its saturated form, closer to the path-traced
    truth, or Yusov's precomputed reference particle: docs/shading.md) and `light_pass` how the light
    reaching it is found (`LIGHT_PASSES`: Harris's multiple forward scattering, Yusov's occlusion
    estimate, Wrenninge's multiple-scattering octaves, or the octaves with the light a lit face sends back;
    "yusov" and "occlusion" together are Yusov's model, "saturated" and "octaves" the octave model:
    docs/shading.md, "Octaves"); `ground_bounce` lights the clouds from below with the ground's bounce in place of
    the ambient's lower half (`cloudcore.light.ground_bounce`)."""

    albedo: float = 0.9
    optical_depth: float = 8.0
    phase: str = "rayleigh"
    g: float = 0.0
    eye_pass: str = "harris"
    light_pass: str = "harris"
    ground_bounce: bool = False


#: the shading a scene made from nothing starts with (`cloudview import` into a new file): the model closest to the
#: path-traced truth at a realistic albedo on the views it was not chosen on (docs/shading.md, "Five views with the
#: lit face in the eye pass: the default for new scenes"); a scene file that does not name its passes keeps
#: `Shading()`'s, Harris's, so the shipped scenes and their golden images keep their pictures
NEW_SCENE_SHADING = Shading(albedo=0.99, eye_pass="saturated", light_pass="octaves-lit-face")


@dataclass(frozen=True, eq=False)
class Cloud(_Record):
    """Particles as rows (x, y, z, radius); optional per-cloud shading overrides and formation.

    `sprite` draws the particles as textured sprites from the atlas instead of
    Gaussian splats (Wang 2004, section 3.2); `artist` shades them with Wang's
    artist model instead of Harris's (section 5), in shading groups of
    `shading_group_size` metres (None: `artist_shading.default_group_size`).
    """

    name: str
    particles: np.ndarray = field(default_factory=lambda: _frozen_array((), 4))
    particles_file: str | None = None
    optical_depth: float | None = None
    albedo: float | None = None
    color: Vec3 = (1.0, 1.0, 1.0)
    formation: Formation | None = None
    sprite: SpriteStyle | None = None
    artist: ArtistShading | None = None
    shading_group_size: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "particles", _frozen_array(self.particles, 4))
        if self.shading_group_size is not None:
            object.__setattr__(self, "shading_group_size", float(self.shading_group_size))

    @property
    def centres(self) -> np.ndarray:
        return self.particles[:, :3]

    @property
    def radii(self) -> np.ndarray:
        return self.particles[:, 3]

    def bounding_sphere(self) -> tuple[np.ndarray, float]:
        """Centre of the particles' box and the radius that encloses every splat (read-only).

        Worked out once: the particles never change, and a particle buffer with a cloud field's hundreds of
        clouds asks every cloud again each time cells come or go.
        """
        held = self.__dict__.get("_bounding_sphere")
        if held is None:
            centre, radius = splats_bounding_sphere(self.centres, self.radii)
            centre.flags.writeable = False
            held = (centre, radius)
            object.__setattr__(self, "_bounding_sphere", held)
        return held


def splats_bounding_sphere(centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre of the splats' box and the radius that encloses every splat ((0, 0, 0), 0 for none)."""
    if len(radii) == 0:
        return np.zeros(3), 0.0
    low = (centres - radii[:, None]).min(axis=0)
    high = (centres + radii[:, None]).max(axis=0)
    centre = 0.5 * (low + high)
    return centre, float((np.linalg.norm(centres - centre, axis=1) + radii).max())


@dataclass(frozen=True, eq=False)
class HeightGrid(_Record):
    """A heightmap's samples over its largest possible value, in [0, 1]: rows along z (the image's top row at
    -z), columns along x.  Hashed by value, as a `Terrain` holding it keys the caches of its tiles."""

    values: np.ndarray

    def __post_init__(self):
        values = np.array(self.values, dtype=np.float64)
        if values.ndim != 2 or min(values.shape) < 2:
            raise FieldError("heightmap", f"expected a grid of at least 2x2 samples, got shape {values.shape}")
        values.flags.writeable = False
        object.__setattr__(self, "values", values)

    def __hash__(self):
        digest = self.__dict__.get("_digest")
        if digest is None:
            digest = hashlib.blake2b(self.values.tobytes(), digest_size=16).digest()
            object.__setattr__(self, "_digest", digest)
        return hash((self.values.shape, digest))


@dataclass(frozen=True)
class Terrain:
    """A procedural heightfield (`cloudcore.world.terrain`), a heightmap image's heights, or a mesh file.

    A "heightmap" terrain's `heights` come from the 16-bit greyscale PNG or the GeoTIFF of elevations `heightmap`
    (relative to the scene file's folder), stretched over `size` with white (the GeoTIFF's highest sample) at
    `height` metres; its `resolution` and `seed` are unused.  Any terrain may be coloured by height
    (`color_ramp`, rows (height_m, r, g, b)) and by slope: from `steep_slope_deg[0]` to `[1]` the colour turns to
    `steep_color`.
    """

    kind: str = "heightfield"
    size: tuple[float, float] = (6000.0, 6000.0)
    resolution: int = 174
    height: float = 650.0
    seed: int = 7
    mesh: str | None = None
    color: Vec3 = (0.32, 0.42, 0.22)
    #: metres the mountains beyond the valley's sides rise (0: none, the valley's hills alone)
    relief: float = 0.0
    #: metres from the origin the ground is drawn to, at least the half of `size` (0: the patch of `size` alone)
    reach: float = 0.0
    heightmap: str | None = None
    #: the heightmap's samples, read by the loader (None for the procedural heightfield)
    heights: HeightGrid | None = None
    color_ramp: tuple[tuple[float, float, float, float], ...] = ()
    steep_color: Vec3 | None = None
    steep_slope_deg: tuple[float, float] = (30.0, 45.0)


@dataclass(frozen=True, eq=False)
class SceneObject(_Record):
    """An opaque object: a mesh file or a built-in primitive, static or on a keyframed path."""

    name: str
    mesh: str | None = None
    primitive: str | None = None
    scale: float = 1.0
    position: Vec3 = (0.0, 0.0, 0.0)
    path: np.ndarray | None = None  # rows (t, x, y, z)
    color: Vec3 = (0.75, 0.75, 0.78)
    #: the mesh file's triangles, read by the loader (None for primitives)
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None

    def __post_init__(self):
        if self.path is not None:
            object.__setattr__(self, "path", _frozen_array(self.path, 4))
        if self.vertices is not None:
            object.__setattr__(self, "vertices", _frozen_array(self.vertices, 3))
            faces = np.array(self.faces, dtype=np.int64).reshape(-1, 3)
            faces.flags.writeable = False
            object.__setattr__(self, "faces", faces)


@dataclass(frozen=True, eq=False)
class CameraPath(_Record):
    """Keys as rows (t, px, py, pz, lx, ly, lz): time, eye position, look-at point."""

    name: str
    keys: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "keys", _frozen_array(self.keys, 7))

    @property
    def duration(self) -> float:
        return float(self.keys[-1, 0] - self.keys[0, 0])


#: the view every scene has: its `[camera]`, its lighting, full 3D (a `[[views]]` entry may not take the name)
DEFAULT_VIEW_NAME = "default"


@dataclass(frozen=True)
class View:
    """A named picture of the scene for screenshot tests (`cloudview check`).

    The eye is at `position` looking at `look_at`, or `t` seconds along the
    camera path named `camera_path`; what a view leaves out (None) is the
    scene's camera's, so a view that only sets `time_of_day` moves with
    `[camera]`.  `time_s` is the scene clock (objects on their paths, clouds
    forming).  `mode` and `settings` (RenderSettings field names and values,
    in file order) say how the clouds are drawn; `tolerance_psnr` and
    `max_diff` override the check's tolerance for this view alone.
    """

    name: str
    position: Vec3 | None = None
    look_at: Vec3 | None = None
    fov_y_deg: float | None = None
    camera_path: str | None = None
    t: float = 0.0
    time_of_day: float | None = None
    time_s: float = 0.0
    mode: str = "full"
    settings: tuple[tuple[str, object], ...] = ()
    tolerance_psnr: float | None = None
    max_diff: int | None = None


#: the most rings a cloud field may have: the outermost's cells are 2^(MAX_RINGS - 1) inner cells across
MAX_RINGS = 12
#: the most particle layers a field's cell may hold
MAX_LAYERS = 8
#: an inner cell's side in metres, at least (smaller would be particles of a few metres) and at most
MIN_CELL_SIZE, MAX_CELL_SIZE = 10.0, 1.0e6
#: a field's extent in inner cells, at most: cell indices stay small integers
MAX_CELLS_ACROSS = 2**31


@dataclass(frozen=True)
class CloudField:
    """Clouds to the horizon as parameters: Yusov's camera-centred nested grid (2014, section 5.2).

    The particles are generated around the eye, cell by cell, by
    `cloudcore.field.cloud_field` (deterministic: the same cell is always the
    same particles).  `coverage` in [0, 1] is how much of the sky is cloud;
    `cell_size` (m) the side of the inner ring's cells, each ring's cells twice
    the size of the ring inside it; `rings` the nested levels; `layers` the
    particle layers of a cell between `altitude` = (bottom, top) in metres;
    `cloud_type` a preset of `cloudcore.artist.cloudgen.PRESETS` (its optics,
    colour and the shape of its towers); the field covers `extent` = (x, z) metres about `centre` = (x, z).
    """

    seed: int = 0
    coverage: float = 0.4
    cell_size: float = 1000.0
    rings: int = 5
    layers: int = 3
    altitude: tuple[float, float] = (1200.0, 2600.0)
    cloud_type: str = "cumulus_humilis"
    extent: tuple[float, float] = (100000.0, 100000.0)
    centre: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        for name in ("seed", "rings", "layers"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise FieldError(name, f"expected an integer, got {value!r}")
            object.__setattr__(self, name, int(value))
        for name, low, high in (("seed", 0, 2**31 - 1), ("rings", 1, MAX_RINGS), ("layers", 1, MAX_LAYERS)):
            if not low <= getattr(self, name) <= high:
                raise FieldError(name, f"must be within [{low}, {high}], got {getattr(self, name)}")
        for name, low, high in (("coverage", 0.0, 1.0), ("cell_size", MIN_CELL_SIZE, MAX_CELL_SIZE)):
            value = float(getattr(self, name))
            if not low <= value <= high:  # NaN fails too
                raise FieldError(name, f"must be within [{low}, {high}], got {value}")
            object.__setattr__(self, name, value)
        for name in ("altitude", "extent", "centre"):
            pair = tuple(float(v) for v in getattr(self, name))
            if len(pair) != 2 or not all(math.isfinite(v) for v in pair):
                raise FieldError(name, f"expected 2 finite numbers, got {list(pair)}")
            object.__setattr__(self, name, pair)
        if not self.altitude[0] < self.altitude[1]:
            raise FieldError(
                "altitude", f"expected [bottom, top] with bottom < top in metres, got {list(self.altitude)}"
            )
        if not all(0.0 < side <= MAX_CELLS_ACROSS * self.cell_size for side in self.extent):
            raise FieldError(
                "extent",
                f"expected [x, z] in metres, each > 0 and at most {MAX_CELLS_ACROSS} cells of cell_size, "
                f"got {list(self.extent)}",
            )


#: the most altitude bands a wind may have
MAX_WIND_BANDS = 16
#: the fastest wind in m/s: past the jet stream's
MAX_WIND_SPEED = 100.0
#: the most a particle strays from its place in its cloud by turbulence, in metres
MAX_TURBULENCE_M = 500.0


@dataclass(frozen=True)
class Wind:
    """The air's motion (`cloudcore.world.wind`): rows (altitude m, speed m/s, direction deg) interpolated by altitude
    (one row: the same wind at every altitude), the direction the meteorological one, the bearing the wind
    blows *from*, clockwise from north (-z): 270 is a westerly, carrying clouds toward +x.  Gusts scale every
    band's speed by 1 + `gust_amplitude` sin(2 pi t / `gust_period_s`).  Turbulence moves each particle about
    its place in its cloud by a divergence-free field at most `turbulence_m` metres, of wavelength
    `turbulence_scale_m` and period `turbulence_period_s`; clouds whose shapes or relative places change are
    relit every `relight_period_s` of the scene clock."""

    bands: tuple[tuple[float, float, float], ...] = ((0.0, 10.0, 270.0),)
    gust_amplitude: float = 0.0
    gust_period_s: float = 60.0
    turbulence_m: float = 0.0
    turbulence_scale_m: float = 400.0
    turbulence_period_s: float = 120.0
    #: 60 s: relighting the default scene took 2.1 to 2.4 s of this machine's CPU (a hitch); its light left at rest
    #: for 55 s of 30 m turbulence was within 45 dB of relit (docs/lod.md, "Clouds that move with the wind")
    relight_period_s: float = 60.0

    def __post_init__(self):
        try:
            bands = tuple(tuple(float(v) for v in row) for row in self.bands)
        except (TypeError, ValueError):
            raise FieldError("bands", f"expected rows of [altitude, speed, direction], got {self.bands!r}") from None
        if not 1 <= len(bands) <= MAX_WIND_BANDS or any(len(row) != 3 for row in bands):
            raise FieldError(
                "bands", f"expected 1 to {MAX_WIND_BANDS} rows of [altitude, speed, direction], got {len(bands)} rows"
            )
        for index, (altitude, speed, direction) in enumerate(bands):
            if not math.isfinite(altitude):
                raise FieldError("bands", f"row {index}: altitude must be finite, got {altitude}")
            if not 0.0 <= speed <= MAX_WIND_SPEED:
                raise FieldError("bands", f"row {index}: speed must be within [0, {MAX_WIND_SPEED:g}] m/s, got {speed}")
            if not 0.0 <= direction <= 360.0:
                raise FieldError("bands", f"row {index}: direction must be within [0, 360] degrees, got {direction}")
        if any(not below[0] < above[0] for below, above in zip(bands, bands[1:])):
            raise FieldError("bands", "altitudes must increase from row to row")
        object.__setattr__(self, "bands", bands)
        _set_bounded_numbers(
            self,
            (
                ("gust_amplitude", 0.0, 1.0),
                ("gust_period_s", 1.0, 3600.0),
                ("turbulence_m", 0.0, MAX_TURBULENCE_M),
                ("turbulence_scale_m", 10.0, 10000.0),
                ("turbulence_period_s", 1.0, 3600.0),
                ("relight_period_s", 0.5, 3600.0),
            ),
        )


def _set_bounded_numbers(record, bounds) -> None:
    """Set each field `name` of the frozen `record` to its value as a float, for each (name, low, high) of `bounds`;
    a value that is no number, or outside [low, high] (NaN among them), is refused naming the field."""
    for name, low, high in bounds:
        value = getattr(record, name)
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise FieldError(name, f"expected a number, got {value!r}")
        value = float(value)
        if not low <= value <= high:  # NaN fails too
            raise FieldError(name, f"must be within [{low:g}, {high:g}], got {value}")
        object.__setattr__(record, name, value)


#: the named weathers of `[weather]` (`cloudcore.field.weather.WEATHER_PRESETS` holds what each sets)
WEATHER_NAMES = ("fair_weather_cumulus", "scattered", "broken", "overcast", "towering_cumulus")


@dataclass(frozen=True)
class Weather:
    """A named weather over a scene's cloud field (`cloudcore.field.weather`): `preset` sets its coverage, cloud type
    and altitudes; with `to`, the weather changes to that one over `duration_s` seconds of the scene clock from
    `start_s`, the coverage following a smoothstep between the two."""

    preset: str = "scattered"
    to: str | None = None
    start_s: float = 0.0
    duration_s: float = 600.0

    def __post_init__(self):
        for name in ("preset", "to"):
            value = getattr(self, name)
            if (value is not None or name == "preset") and value not in WEATHER_NAMES:
                raise FieldError(name, f"{value!r} is not one of: {', '.join(WEATHER_NAMES)}")
        _set_bounded_numbers(self, (("start_s", -1.0e9, 1.0e9), ("duration_s", 1.0, 86400.0)))


@dataclass(frozen=True)
class Scene:
    camera: Camera = Camera()
    lighting: Lighting = Lighting()
    shading: Shading = Shading()
    clouds: tuple[Cloud, ...] = ()
    terrain: Terrain | None = None
    objects: tuple[SceneObject, ...] = ()
    camera_paths: tuple[CameraPath, ...] = ()
    description: str = ""
    #: the named views of `[[views]]`; `all_views` adds the default one first
    views: tuple[View, ...] = ()
    #: clouds generated around the eye to the horizon (`[cloud_field]`), besides the authored `clouds`
    cloud_field: CloudField | None = None
    #: the air's motion (`[wind]`): the clouds drift and churn with the scene clock; None: still air
    wind: Wind | None = None
    #: named weather over the cloud field (`[weather]`), changing with the scene clock; None: the field's own keys
    weather: Weather | None = None

    @property
    def particle_count(self) -> int:
        return sum(len(c.particles) for c in self.clouds)

    def camera_path(self, name: str) -> CameraPath:
        for path in self.camera_paths:
            if path.name == name:
                return path
        known = ", ".join(p.name for p in self.camera_paths) or "none"
        raise KeyError(f"no camera path named {name!r}; the scene has: {known}")

    @property
    def all_views(self) -> tuple[View, ...]:
        """The default view (the scene's camera and lighting, full 3D), then the named ones."""
        return (View(DEFAULT_VIEW_NAME), *self.views)
