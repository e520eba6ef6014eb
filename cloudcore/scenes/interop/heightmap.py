"""Heightmaps: greyscale PNG images and GeoTIFF elevation models read as terrain heights, 16 bits kept, and
written for the examples.

The image's header is read and checked before a pixel is decoded: a file that claims 10^12 pixels is refused
from its first bytes, not after the memory is gone.  Any problem is one `SceneError` naming the file; the heights
come back whole or not at all.

A PNG's samples are heights over its white, which the scene's `height` places.  A GeoTIFF (one band of
elevations, integer or float, as DEMs are published) holds metres: its lowest sample becomes the ground's 0, its
highest the height its rise gives, and where it is georeferenced (its pixel scale, in metres or, for longitude
and latitude, converted at its middle latitude) the extent it covers.  Pillow, which the project has for PNG,
reads the TIFF and its tags: no GDAL.
"""

from __future__ import annotations

import hashlib
import io
import math
import struct
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cloudcore.model.errors import SceneError
from cloudcore.model.particle_files import atomic_write
from cloudcore.scenes.limits import MAX_MAGNITUDE

#: samples along a heightmap's side, at most: 4097^2 float64 heights are 134 MB, and the finest tiles' cells
#: (the image's pixels) are 1.5 m across the default 6 km patch
MAX_HEIGHTMAP_SIDE = 4097
#: a heightmap file's bytes, at most (a 4097^2 16-bit image, uncompressed, is 34 MB)
MAX_HEIGHTMAP_BYTES = 64 * 2**20
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: PNG's colour type of greyscale without alpha, and the bit depths read (8 or 16 bits a sample)
_GREYSCALE = 0
_BIT_DEPTHS = (8, 16)


#: a TIFF file's first bytes, little- and big-endian
TIFF_SIGNATURES = (b"II*\x00", b"MM\x00*")
#: GeoTIFF's tags: the pixel's size in model units, the tie of a pixel to a model point, the GeoKey directory,
#: and GDAL's no-data value (ASCII)
_PIXEL_SCALE, _TIEPOINT, _GEO_KEYS, _NO_DATA = 33550, 33922, 34735, 42113
#: GeoKeys: the model's type (1 projected, 2 geographic) and a projected model's linear unit
_MODEL_TYPE, _LINEAR_UNITS = 1024, 3076
_PROJECTED, _GEOGRAPHIC = 1, 2
#: metres of EPSG's linear units: the metre, the foot and the US survey foot
_METRES_PER_UNIT = {9001: 1.0, 9002: 0.3048, 9003: 1200.0 / 3937.0}
#: metres of a degree of latitude, and of longitude at the equator (WGS 84, near enough for a terrain's extent)
_METRES_PER_DEGREE_LATITUDE, _METRES_PER_DEGREE_LONGITUDE = 110_574.0, 111_320.0
#: the sample types read from a TIFF (Pillow's modes): 8, 16 and 32-bit integers, 32-bit floats
_TIFF_MODES = ("L", "I;16", "I;16B", "I;16S", "I", "F")


@dataclass(frozen=True)
class Heightmap:
    """A heightmap file's heights and what it says of its place."""

    heights: np.ndarray  # (rows, columns) in [0, 1]
    #: metres from the lowest sample to the highest, where the file holds elevations (a GeoTIFF); None for a PNG,
    #: whose white the scene's `height` places
    rise_m: float | None = None
    #: metres (along x, along z) the file's georeferencing spans; None where it has none
    extent_m: tuple[float, float] | None = None


def read_heightmap(path) -> np.ndarray:
    """The heights (rows, columns) in [0, 1] of the heightmap at `path` (`read_heightmap_file`'s)."""
    return read_heightmap_file(path).heights


def read_heightmap_file(path) -> Heightmap:
    """The heightmap at `path`: an 8- or 16-bit greyscale PNG (each sample over the largest its bit depth holds,
    65535 for 16 bits) or a GeoTIFF of elevations (`Heightmap`).  SceneError (naming the file) for anything else."""
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise SceneError(source, "heightmap", "no such file" if not path.exists() else "not a regular file")
    if path.stat().st_size > MAX_HEIGHTMAP_BYTES:
        raise SceneError(source, "heightmap", f"{path.stat().st_size:,} bytes, at most {MAX_HEIGHTMAP_BYTES:,}")
    data = path.read_bytes()
    if data[:4] in TIFF_SIGNATURES:
        return _read_geotiff(source, data)
    return Heightmap(_read_png(source, data))


def _read_png(source: str, data: bytes) -> np.ndarray:
    from PIL import Image

    width, height, depth = _checked_header(source, data)
    try:
        with Image.open(io.BytesIO(data), formats=["PNG"]) as image:
            image.load()
            samples = np.asarray(image)
    except Exception as error:  # Pillow raises OSError, SyntaxError, ValueError, zlib.error... on a bad file
        raise SceneError(source, "heightmap", f"not a readable PNG (truncated or corrupt?): {error}") from None
    if samples.shape != (height, width):
        raise SceneError(source, "heightmap", f"decoded as {samples.shape}, its header says {height}x{width}")
    return samples.astype(np.float64) / (2**depth - 1)


def _read_geotiff(source: str, data: bytes) -> Heightmap:
    """A GeoTIFF's one band of elevations, its size checked from its header before a sample is decoded."""
    from PIL import Image, UnidentifiedImageError

    unreadable = "not a readable TIFF (truncated or corrupt?)"
    with warnings.catch_warnings():  # Pillow warns of what it cannot read, then fails: the failure is the message
        warnings.simplefilter("ignore")
        try:
            image = Image.open(io.BytesIO(data), formats=["TIFF"])
        except Image.DecompressionBombError:  # Pillow's own bound, past ours, checked as it reads the header
            raise SceneError(
                source,
                "heightmap",
                f"its header claims over {Image.MAX_IMAGE_PIXELS:.3g} pixels, each side must be within"
                f" [2, {MAX_HEIGHTMAP_SIDE}]",
            ) from None
        except UnidentifiedImageError:  # its message names Pillow's buffer, not the file
            raise SceneError(source, "heightmap", unreadable) from None
        except Exception as error:  # a forged header raises anything from OSError to struct.error
            raise SceneError(source, "heightmap", f"{unreadable}: {error}") from None
        with image:
            width, height = image.size
            _check_side(source, width, height)
            if image.mode not in _TIFF_MODES or getattr(image, "n_frames", 1) != 1:
                raise SceneError(
                    source,
                    "heightmap",
                    f"expected one band of elevations, got Pillow's mode {image.mode!r} (one band: grey)",
                )
            tags = dict(image.tag_v2)
            try:
                image.load()
                samples = np.asarray(image, dtype=np.float64)
            except Exception as error:
                raise SceneError(source, "heightmap", f"{unreadable}: {error}") from None
    if samples.shape != (height, width):
        raise SceneError(source, "heightmap", f"decoded as {samples.shape}, its header says {height}x{width}")
    missing = ~np.isfinite(samples)
    no_data = tags.get(_NO_DATA)
    if no_data is not None:
        try:
            missing |= samples == float(str(no_data).strip("\x00 "))
        except ValueError:
            raise SceneError(source, "heightmap", f"its no-data value {no_data!r} is not a number") from None
    if missing.any():
        raise SceneError(
            source,
            "heightmap",
            f"{np.count_nonzero(missing):,} of its {samples.size:,} samples hold no elevation (no-data or not finite):"
            " fill them first",
        )
    if np.abs(samples).max() > MAX_MAGNITUDE:
        raise SceneError(source, "heightmap", f"an elevation of {np.abs(samples).max():.3g}, at most {MAX_MAGNITUDE:g}")
    low, rise = float(samples.min()), float(np.ptp(samples))
    heights = (samples - low) / rise if rise > 0.0 else np.zeros_like(samples)
    return Heightmap(np.clip(heights, 0.0, 1.0), rise, _georeferenced_extent(tags, width, height))


def _georeferenced_extent(tags: dict, width: int, height: int) -> tuple[float, float] | None:
    """Metres (along x, along z) a GeoTIFF's `width` x `height` pixels span, from its pixel scale: in a projected
    model's linear unit, or in degrees of a geographic model at its middle latitude; None where it says neither."""
    scale, keys = tags.get(_PIXEL_SCALE), tags.get(_GEO_KEYS)
    if scale is None or keys is None or len(scale) < 2 or len(keys) < 4:
        return None
    geo_keys = {keys[i]: keys[i + 3] for i in range(4, min(len(keys), 4 + 4 * keys[3]) - 3, 4) if keys[i + 1] == 0}
    across, down = abs(float(scale[0])) * width, abs(float(scale[1])) * height
    model = geo_keys.get(_MODEL_TYPE)
    if model == _PROJECTED:
        metres = _METRES_PER_UNIT.get(geo_keys.get(_LINEAR_UNITS, 9001))
        extent = None if metres is None else (across * metres, down * metres)
    elif model == _GEOGRAPHIC:
        tie = tags.get(_TIEPOINT)
        latitude = float(tie[4]) - 0.5 * down if tie is not None and len(tie) >= 6 else 0.0
        extent = (
            across * _METRES_PER_DEGREE_LONGITUDE * math.cos(math.radians(min(abs(latitude), 90.0))),
            down * _METRES_PER_DEGREE_LATITUDE,
        )
    else:
        return None
    return extent if extent is not None and all(math.isfinite(v) and v > 0.0 for v in extent) else None


def _check_side(source: str, width: int, height: int) -> None:
    if not (2 <= width <= MAX_HEIGHTMAP_SIDE and 2 <= height <= MAX_HEIGHTMAP_SIDE):
        raise SceneError(
            source,
            "heightmap",
            f"{width}x{height} pixels ({width * height:.3g}), each side must be within [2, {MAX_HEIGHTMAP_SIDE}]",
        )


def _checked_header(source: str, data: bytes) -> tuple[int, int, int]:
    """(width, height, bit depth) from the PNG's IHDR chunk, checked against what can be read."""
    if data[:8] != PNG_SIGNATURE:
        raise SceneError(source, "heightmap", "neither a PNG nor a TIFF file (its first bytes are neither's signature)")
    if len(data) < 33 or data[12:16] != b"IHDR":
        raise SceneError(source, "heightmap", "a PNG without its header chunk (truncated?)")
    width, height, depth, colour_type = struct.unpack(">IIBB", data[16:26])
    if zlib.crc32(data[12:29]) != struct.unpack(">I", data[29:33])[0]:
        raise SceneError(source, "heightmap", "its header chunk is corrupt (CRC mismatch)")
    _check_side(source, width, height)
    if colour_type != _GREYSCALE or depth not in _BIT_DEPTHS:
        raise SceneError(
            source,
            "heightmap",
            f"expected 8- or 16-bit greyscale, got colour type {colour_type} of {depth} bits (convert to grey)",
        )
    return width, height, depth


def write_heightmap(path, heights: np.ndarray) -> None:
    """Write `heights` (rows, columns) in [0, 1] to a 16-bit greyscale PNG at `path`, atomically."""
    from PIL import Image

    heights = np.asarray(heights, dtype=np.float64)
    if heights.ndim != 2 or not np.all((heights >= 0.0) & (heights <= 1.0)):
        raise ValueError("heights must be a 2D grid within [0, 1]")
    samples = np.round(heights * 65535.0).astype(np.uint16)
    out = io.BytesIO()
    Image.fromarray(samples).save(out, format="PNG", optimize=True)
    atomic_write(Path(path), lambda f: f.write(out.getvalue()))


def store_heightmap(heights: np.ndarray, wanted: str, scene_path: Path) -> str:
    """The heightmap file, relative to the scene at `scene_path`, that holds `heights` (in [0, 1], 16-bit
    levels), written if need be: `wanted` where it lies in the scene's folder and holds them or is free, else
    `<scene>.heightmap.png`, else a name with their digest.  A file holding other heights is never overwritten
    (the scene file on disk may still name it until the save's rename commits it), so a scene saved into
    another folder takes its heightmap along."""
    folder = Path(scene_path).parent.resolve()
    digest = hashlib.sha256(np.ascontiguousarray(heights).tobytes()).hexdigest()[:16]
    stem = Path(scene_path).stem
    candidates = [f"{stem}.heightmap.png", f"{stem}.heightmap-{digest}.png"]
    if wanted and not Path(wanted).is_absolute() and (folder / wanted).resolve().is_relative_to(folder):
        candidates.insert(0, wanted)
    for relative in candidates:
        file = folder / relative
        if not file.exists():
            file.parent.mkdir(parents=True, exist_ok=True)
            write_heightmap(file, heights)
            return relative
        if _holds(file, heights):
            return relative
    raise SceneError(str(folder / candidates[-1]), "heightmap", "holds other heights: move it away to save here")


def _holds(file: Path, heights: np.ndarray) -> bool:
    try:
        return np.array_equal(read_heightmap(file), heights)
    except SceneError:
        return False
