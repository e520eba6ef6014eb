"""What the renderer can draw, checked where a scene comes in: when a file is loaded and when the editor changes it.

The GL side has hard limits of its own (a shader array, the kinds of terrain
it can mesh, integer cell numbers); a scene past one used to load and then end
in a traceback from the renderer.  The limits live here, on the pure side (no
OpenGL import), so the GL code takes its constants from this module and the
scene loader (`cloudcore.scenes.files`: one line naming file and field, exit 2)
and the editor (`app.editor.Editor.edit`: a message, the scene kept) refuse
such a scene first.  docs/scene-format.md lists them.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from cloudcore.artist.artist_shading import default_group_size, shading_grid_fits
from cloudcore.atmosphere.aerial_perspective import MAX_DISTANCE_M
from cloudcore.light.lighting import active_lights
from cloudcore.light.phase import MAX_ABS_G
from cloudcore.model.scene import Air, Camera, Cloud, Light, Lighting, SceneObject, Shading, Terrain, View

#: lights that shine on clouds at once: the compute shader keeps one incident term per light
#: per particle (`incident[MAX_LIGHTS]` in gl/shaders/splat_shade.comp.glsl)
MAX_LIGHTS = 8
#: the terrain kinds the world pass can draw (gl/world.py meshes heightfields, procedural or from a heightmap)
DRAWN_TERRAIN_KINDS = ("heightfield", "heightmap")
#: the largest side of a frame in pixels (llvmpipe's and most GPUs' largest renderbuffer)
MAX_FRAME_SIDE = 16384
#: the memory a frame of the headless commands takes, per pixel and whatever its size: the peak resident size
#: of `cloudview render` on llvmpipe, whose targets are in the process's memory, on the default scene in auto
#: mode (its impostors' targets too) was 0.64, 1.16 and 3.06 GB at 2048, 4096 and 8192 pixels square
#: (2026-12-06): 40-43 bytes a pixel over about 475 MB.  A 16384x16384 frame, within MAX_FRAME_SIDE, was
#: killed for memory at 24 GB when the read-back's colour conversion took the whole frame at once
FRAME_BYTES_PER_PIXEL = 48
FRAME_BASE_BYTES = 512 * 2**20
#: the largest magnitude of any number a scene holds (metres, seconds, optical depths, colours, intensities):
#: the product of three such stays finite in float32 (3.4e38) on the GPU and in its half-float targets' sums,
#: and a float64 position keeps a tenth of a millimetre.  A camera 1e20 m out made the view singular, a
#: particle at 1e200 m overflowed the shading's distances, an ambient of 1e39 put Inf in the frame
MAX_MAGNITUDE = 1.0e12
#: the longest name of a cloud, object, camera path or view, in characters: names become file names (a
#: cloud's particles, a view's golden), and a 240-character cloud name made every save fail
MAX_NAME_LENGTH = 64
#: the range of each bounded number of a scene, by record and field (a vector's by component): the scene loader
#: reads each within it and the editor refuses an edit past it.  A typed albedo of 2 or time of day of 30 was
#: applied, saved to a file that would not open again and failed the viewport's shading every frame
FIELD_RANGES = {
    (Camera, "fov_y_deg"): (1.0, 170.0),
    (View, "fov_y_deg"): (1.0, 170.0),
    (Lighting, "time_of_day"): (0.0, 24.0),
    (View, "time_of_day"): (0.0, 24.0),
    (Lighting, "ambient"): (0.0, math.inf),
    (Light, "color"): (0.0, math.inf),
    # Earth's clear aerosols (Mie optical depth 0.005) to 100 times them (0.53, thick haze): there the sky's tables
    # were checked against a fine march (within 3%, as for clear air); denser is fog, whose light the tables'
    # 40 samples a ray and single scattering with psi_ms were not checked for (docs/atmosphere.md)
    (Air, "mie_density_scale"): (0.0, 100.0),
    (Air, "ground_albedo"): (0.0, 1.0),
    # the ground of the planet (sea level) to 50 km, well inside the air's 100 km: the sky is the one seen from
    # the origin, and the clouds stand above it
    (Air, "origin_altitude_m"): (0.0, 50_000.0),
    (Light, "intensity"): (0.0, math.inf),
    (Shading, "albedo"): (0.0, 1.0),
    (Shading, "optical_depth"): (0.0, math.inf),
    (Shading, "g"): (-MAX_ABS_G, MAX_ABS_G),
    (Cloud, "albedo"): (0.0, 1.0),
    (Cloud, "optical_depth"): (0.0, math.inf),
    (Cloud, "color"): (0.0, math.inf),
    (Terrain, "height"): (0.0, math.inf),
    # mountains up to 8 km: the aerial-perspective volume and the sky's tables stop short of the air's top
    (Terrain, "relief"): (0.0, 8000.0),
    # to the aerial-perspective volume's last slice (`MAX_DISTANCE_M`): the air past it is not looked up
    (Terrain, "reach"): (0.0, MAX_DISTANCE_M),
    (Terrain, "color"): (0.0, 1.0),
    (Terrain, "steep_color"): (0.0, 1.0),
    (Terrain, "steep_slope_deg"): (0.0, 90.0),
    (SceneObject, "color"): (0.0, 1.0),
    (View, "tolerance_psnr"): (0.0, math.inf),
}
_UNBOUNDED = (-math.inf, math.inf)
#: where a record's field is not the scene file's key: an object's vertices come from its mesh file, a
#: terrain's heights from its heightmap
_FILE_KEYS = {"vertices": "mesh", "heights": "heightmap"}


def scene_limit_problems(scene, unchanged=None) -> list[tuple[str, str]]:
    """(field, problem) for each limit `scene` is past, fields as the scene file names them.

    `unchanged`: a scene whose clouds and terrain, where they are the very same objects, need
    no second look (the editor checks every edit; most leave most clouds and the terrain alone).
    """
    problems = []
    if scene.lighting.lights:
        shining = len(active_lights(scene.lighting.lights))
        if shining > MAX_LIGHTS:
            problems.append(
                (
                    "lighting.lights",
                    f"at most {MAX_LIGHTS} lights can shine on clouds at once, "
                    f"the scene has {shining} (lights of intensity 0 or black do not count)",
                )
            )
    if scene.terrain is not None and scene.terrain.kind not in DRAWN_TERRAIN_KINDS:
        problems.append(
            (
                "terrain.kind",
                f"the renderer draws {' or '.join(DRAWN_TERRAIN_KINDS)} terrain only, not {scene.terrain.kind!r}",
            )
        )
    if scene.weather is not None and scene.cloud_field is None:
        problems.append(("weather", "a weather sets a cloud field's coverage: the scene has no [cloud_field]"))
    previous = {id(cloud) for cloud in unchanged.clouds} if unchanged is not None else set()
    for key in (
        "camera",
        "lighting",
        "shading",
        "terrain",
        "objects",
        "camera_paths",
        "views",
        "cloud_field",
        "wind",
        "weather",
    ):
        # a terrain left alone needs no second look: a 4097^2 heightmap's samples took 0.29 s every edit
        if key != "terrain" or unchanged is None or scene.terrain is not unchanged.terrain:
            problems.extend(_out_of_bounds(key, getattr(scene, key)))
    if scene.terrain is not None:
        problems.extend(_terrain_problems(scene.terrain))
    for i, path in enumerate(scene.camera_paths):  # the editor moves and deletes keys
        problem = camera_path_keys_problem(path.keys)
        if problem is not None:
            problems.append((f"camera_paths[{i}].keys", problem))
    for i, cloud in enumerate(scene.clouds):
        if id(cloud) in previous:
            continue
        problems.extend(_out_of_bounds(f"clouds[{i}]", cloud))
        not_positive = np.flatnonzero(~(cloud.radii > 0))
        if not_positive.size:
            field = "particles" if cloud.particles_file is None else "particles_file"
            row = not_positive[0]
            problems.append((f"clouds[{i}].{field}", f"radius must be > 0 (row {row} has {cloud.radii[row]})"))
        if cloud.artist is None or not len(cloud.particles):
            continue
        size = cloud.shading_group_size or default_group_size(cloud.radii)
        if not shading_grid_fits(cloud.centres, size):
            field = "shading_group_size" if cloud.shading_group_size else "particles"
            problems.append(
                (
                    f"clouds[{i}].{field}",
                    f"shading groups of {size:g} m are too small for a cloud this "
                    "large (more than 2**53 groups across)",
                )
            )
    return problems


def camera_path_keys_problem(keys: np.ndarray) -> str | None:
    """What is wrong with a camera path's keys (rows t, eye, look-at) for playing them, or None: at least two,
    their times increasing, no key looking at its own eye."""
    if len(keys) < 2:
        return "a camera path needs at least 2 keys"
    if np.any(np.diff(keys[:, 0]) <= 0):
        return "key times must increase strictly"
    if np.any(np.all(keys[:, 1:4] == keys[:, 4:7], axis=1)):
        return "a key looks at its own position"
    return None


def _terrain_problems(terrain: Terrain) -> Iterator[tuple[str, str]]:
    """What a terrain's fields must agree on: a heightmap terrain has heights (and only it), a colour ramp's
    heights increase and its colours are within [0, 1], the steep colour turns in over a range of slopes."""
    if (terrain.kind == "heightmap") != (terrain.heights is not None):
        yield "terrain.heightmap", "heights come from a heightmap, for a terrain of kind 'heightmap' alone"
    if terrain.color_ramp:
        ramp = np.array(terrain.color_ramp, dtype=np.float64)
        if ramp.ndim != 2 or ramp.shape[1] != 4:
            yield "terrain.color_ramp", f"expected rows [height_m, r, g, b], got {terrain.color_ramp!r}"
        elif not np.all(np.isfinite(ramp)):
            return  # `_out_of_bounds` names the number
        elif np.any(np.diff(ramp[:, 0]) <= 0.0):
            yield "terrain.color_ramp", "the rows' heights must increase strictly"
        elif not np.all((ramp[:, 1:] >= 0.0) & (ramp[:, 1:] <= 1.0)):
            yield "terrain.color_ramp", "colours must be within [0, 1]"
    low, high = terrain.steep_slope_deg
    if not low < high:
        yield "terrain.steep_slope_deg", f"expected [from, to] with from < to in degrees, got {[low, high]}"


def _out_of_bounds(field: str, value, bounds=_UNBOUNDED, infinite_allowed=False) -> Iterator[tuple[str, str]]:
    """(field, problem) for each number in `value` (a record, a tuple, an array) that is not finite, past
    MAX_MAGNITUDE or out of its FIELD_RANGES, and each name past MAX_NAME_LENGTH.  A view's settings may be
    infinite (a ring radius): RenderSettings checks them."""
    if dataclasses.is_dataclass(value):
        for item in dataclasses.fields(value):
            name = _FILE_KEYS.get(item.name, item.name)
            if item.name == "particles" and getattr(value, "particles_file", None) is not None:
                name = "particles_file"  # the cloud's particles are in that file, not in the scene's
            inner = getattr(value, item.name)
            if item.name == "name" and isinstance(inner, str) and len(inner) > MAX_NAME_LENGTH:
                yield (
                    f"{field}.name",
                    f"at most {MAX_NAME_LENGTH} characters (names become file names), got {len(inner)}",
                )
            elif item.name == "settings" and isinstance(inner, tuple):  # a view's (setting, value): keys of its table
                for key, setting in inner:
                    yield from _out_of_bounds(f"{field}.{key}", setting, infinite_allowed=True)
            else:
                inner_bounds = FIELD_RANGES.get((type(value), item.name), _UNBOUNDED)
                yield from _out_of_bounds(f"{field}.{name}", inner, inner_bounds)
    elif isinstance(value, (tuple, list)) and value and all(dataclasses.is_dataclass(item) for item in value):
        for i, item in enumerate(value):
            yield from _out_of_bounds(f"{field}[{i}]", item)
    else:
        numbers = _floats(value)
        if not numbers.size:
            return
        finite = np.isfinite(numbers)
        allowed = ~np.isnan(numbers) if infinite_allowed else finite
        low, high = bounds
        if not allowed.all():
            yield field, f"numbers must be finite, got {numbers[~allowed][0]}"
        elif (largest := float(np.abs(numbers[finite]).max(initial=0.0))) > MAX_MAGNITUDE:
            yield field, f"numbers must be within +-{MAX_MAGNITUDE:g}, got {largest:.3g}"
        elif numbers.min() < low or numbers.max() > high:
            outside = numbers[(numbers < low) | (numbers > high)][0]
            yield field, f"must be within [{low:g}, {high:g}], got {outside:g}"


def _floats(value) -> np.ndarray:
    """The floats of a value, flat: a number, a float array, or tuples of them nested (none where there are none;
    strings and integers are not magnitudes: names, choices, counts, seeds)."""
    if isinstance(value, np.ndarray):
        return value.ravel() if value.dtype.kind == "f" else np.empty(0)
    if isinstance(value, (tuple, list)):
        return np.concatenate([np.empty(0), *(_floats(item) for item in value)])
    if isinstance(value, (float, np.floating)):
        return np.array([float(value)])
    return np.empty(0)


def frame_memory_problem(width: int, height: int, available_bytes: int | None = None) -> str | None:
    """Why a `width` x `height` frame would not fit in the memory available (`available_bytes`, else this
    machine's), or None where it fits or the available memory is unknown."""
    available = available_memory_bytes() if available_bytes is None else available_bytes
    needed = FRAME_BASE_BYTES + FRAME_BYTES_PER_PIXEL * width * height
    if available is None or needed <= available:
        return None
    return (
        f"a {width}x{height} frame needs about {needed / 1e9:.1f} GB of memory "
        f"({FRAME_BYTES_PER_PIXEL} bytes a pixel), {available / 1e9:.1f} GB are available"
    )


def available_memory_bytes() -> int | None:
    """What the kernel says new allocations can take without swapping (Linux's MemAvailable), else None."""
    try:
        with open("/proc/meminfo") as info:
            for line in info:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None
