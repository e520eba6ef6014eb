"""Heightmaps: greyscale PNG images read as terrain heights, 16 bits kept, and written for the examples.

The image's header is read and checked before Pillow decodes a pixel: a file that claims 10^12 pixels is
refused from its first 33 bytes, not after the memory is gone.  Any problem is one `SceneError` naming the
file; the heights come back whole or not at all.
"""

from __future__ import annotations

import hashlib
import io
import struct
import zlib
from pathlib import Path

import numpy as np

from cloudcore.errors import SceneError
from cloudcore.particle_files import atomic_write

#: samples along a heightmap's side, at most: 4097^2 float64 heights are 134 MB, and the finest tiles' cells
#: (the image's pixels) are 1.5 m across the default 6 km patch
MAX_HEIGHTMAP_SIDE = 4097
#: a heightmap file's bytes, at most (a 4097^2 16-bit image, uncompressed, is 34 MB)
MAX_HEIGHTMAP_BYTES = 64 * 2**20
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: PNG's colour type of greyscale without alpha, and the bit depths read (8 or 16 bits a sample)
_GREYSCALE = 0
_BIT_DEPTHS = (8, 16)


def read_heightmap(path) -> np.ndarray:
    """The heights (rows, columns) in [0, 1] of the 8- or 16-bit greyscale PNG at `path`: each sample over the
    largest its bit depth holds (65535 for 16 bits).  SceneError (naming the file) for anything else."""
    from PIL import Image

    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise SceneError(source, "heightmap", "no such file" if not path.exists() else "not a regular file")
    if path.stat().st_size > MAX_HEIGHTMAP_BYTES:
        raise SceneError(source, "heightmap", f"{path.stat().st_size:,} bytes, at most {MAX_HEIGHTMAP_BYTES:,}")
    data = path.read_bytes()
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


def _checked_header(source: str, data: bytes) -> tuple[int, int, int]:
    """(width, height, bit depth) from the PNG's IHDR chunk, checked against what can be read."""
    if data[:8] != PNG_SIGNATURE:
        raise SceneError(source, "heightmap", "not a PNG file (its first bytes are not PNG's signature)")
    if len(data) < 33 or data[12:16] != b"IHDR":
        raise SceneError(source, "heightmap", "a PNG without its header chunk (truncated?)")
    width, height, depth, colour_type = struct.unpack(">IIBB", data[16:26])
    if zlib.crc32(data[12:29]) != struct.unpack(">I", data[29:33])[0]:
        raise SceneError(source, "heightmap", "its header chunk is corrupt (CRC mismatch)")
    if not (2 <= width <= MAX_HEIGHTMAP_SIDE and 2 <= height <= MAX_HEIGHTMAP_SIDE):
        raise SceneError(
            source,
            "heightmap",
            f"{width}x{height} pixels ({width * height:.3g}), each side must be within [2, {MAX_HEIGHTMAP_SIDE}]",
        )
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
