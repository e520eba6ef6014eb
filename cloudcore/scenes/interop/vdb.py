"""OpenVDB files: float density grids read and written through tinyvdb (wheels only, no libopenvdb).

A grid here is its active voxels, sparse: their index coordinates, their values (float64) and the grid's
transform, world = index @ linear + translation (OpenVDB's row-vector convention: voxel (i, j, k) is centred
at index point (i, j, k)).  Reading checks everything a later step would trust, and any problem is one
`SceneError` naming the file and the grid; writing is atomic.

tinyvdb 0.9 can rebuild a grid's tree from sparse voxels but cannot start a file: `_template` writes the
part of the format it reuses (header, grid descriptors, metadata, transform, an empty tree) and tinyvdb
fills the trees and compresses them.
"""

from __future__ import annotations

import struct
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cloudcore.model.errors import SceneError
from cloudcore.model.particle_files import atomic_write
from cloudcore.scenes.limits import MAX_MAGNITUDE, MAX_NAME_LENGTH

#: active voxels of one grid, at most: the fit holds about 100 bytes a voxel (float64 positions, neighbour
#: lists), so 2^25 voxels (a dense 320^3 cloud, a sparse one far larger) stay within a few GB
MAX_GRID_VOXELS = 2**25
#: a voxel's side must be at least this fraction of the grid's largest coordinate, else float64 positions of
#: neighbouring voxels are no longer apart (and a zero or denormal scale is refused)
MIN_RELATIVE_VOXEL = 1e-9
#: the tree layout of every float grid OpenVDB, Houdini and Blender write (5-4-3 node log2 sizes)
FLOAT_TREE = "Tree_float_5_4_3"
#: OpenVDB's file magic, and the format version written (224: per-grid compression, the one tinyvdb writes)
VDB_MAGIC = 0x56444220
VDB_FILE_VERSION = 224


@dataclass(frozen=True, eq=False)
class DensityGrid:
    """A float grid's active voxels: `voxels` (n, 3) int64 index coordinates, `density` (n,) float64, and
    the transform world = voxels @ linear + translation."""

    name: str
    voxels: np.ndarray
    density: np.ndarray
    linear: np.ndarray
    translation: np.ndarray

    def world_points(self) -> np.ndarray:
        """(n, 3) the active voxels' centres in the world."""
        return self.voxels @ self.linear + self.translation

    @property
    def voxel_volume(self) -> float:
        return abs(float(np.linalg.det(self.linear)))


def read_density_grids(path) -> list[DensityGrid]:
    """Every float grid of the OpenVDB file at `path`, checked (finite, non-negative, an invertible finite
    transform, at most MAX_GRID_VOXELS voxels, a zero background); SceneError otherwise."""
    import tinyvdb

    path = Path(path)
    source = str(path)
    if not path.exists():
        raise SceneError(source, "(file)", "no such file")
    if not path.is_file():
        raise SceneError(source, "(file)", "not a regular file (a folder, a pipe or a device)")
    try:
        with tinyvdb.open(source) as file:
            file.read_grids()
            grids = [_read_grid(source, file.grid(i)) for i in range(file.grid_count)]
    except tinyvdb.VDBError as error:
        raise SceneError(source, "(file)", f"not a readable OpenVDB file (truncated or corrupt?): {error}") from None
    except OSError as error:
        raise SceneError(source, "(file)", f"cannot read: {error}") from None
    grids = [grid for grid in grids if grid is not None]
    if not grids:
        raise SceneError(source, "(file)", "holds no float grid with density in it")
    return grids


def _read_grid(source: str, grid) -> DensityGrid | None:
    """The grid as a DensityGrid, or None where it is not a float grid or holds no density."""
    if not grid.type_name.startswith("Tree_float_"):
        return None
    field = f"grid {grid.name[:MAX_NAME_LENGTH]!r}"
    if (grid.metadata or {}).get("class") == "level set":
        raise SceneError(source, field, "a level set (signed distances), not a density")
    background = grid.float_background()
    if background != 0.0:
        raise SceneError(source, field, f"its background is {background}, a density that would fill all space")
    count = grid.active_voxel_count()
    if count > MAX_GRID_VOXELS:
        raise SceneError(source, field, f"{count:,} active voxels, at most {MAX_GRID_VOXELS:,} can be imported")
    linear, translation = _transform(source, field, grid.transform)
    if count == 0:
        return None
    sparse = grid.to_sparse()
    voxels = np.frombuffer(sparse["coords"], dtype=np.int32).reshape(-1, 3).astype(np.int64)
    density = np.frombuffer(sparse["values"], dtype=np.float32).astype(np.float64)
    tree = grid.tree
    in_leaves = sum(node.active_voxel_count for node in map(tree.node, range(tree.num_nodes)) if node.type == "leaf")
    if not len(voxels) == len(density) == in_leaves:
        # tinyvdb 0.9.0 walks a tree with a stack of 64 leaves: the voxels of the leaves past it are dropped without
        # a word (a dense 40^3 grid, 125 leaves, gave 32,768 voxels); its repository has the fix, no release yet
        raise SceneError(
            source,
            field,
            f"tinyvdb {tinyvdb_version()} read only {len(voxels):,} of its {in_leaves:,} active voxels (that release "
            "drops the leaves of a tree past its 64th): split the grid or coarsen it",
        )
    bad = np.flatnonzero(~np.isfinite(density) | (density < 0.0))
    if bad.size:
        voxel = tuple(int(v) for v in voxels[bad[0]])
        raise SceneError(source, field, f"density must be finite and >= 0, voxel {voxel} holds {density[bad[0]]}")
    corners = np.array([voxels.min(axis=0), voxels.max(axis=0)]) @ linear + translation
    if not np.all(np.abs(corners) <= MAX_MAGNITUDE):
        raise SceneError(source, field, f"its voxels reach {np.abs(corners).max():.3g} m, past +-{MAX_MAGNITUDE:g}")
    extent = float(np.abs(corners).max())
    if np.cbrt(abs(np.linalg.det(linear))) < MIN_RELATIVE_VOXEL * extent:
        raise SceneError(source, field, "its voxels are too small for their distance from the origin")
    keep = density > 0.0
    if not keep.any():
        return None
    return DensityGrid(grid.name, voxels[keep], density[keep], linear, translation)


def tinyvdb_version() -> str:
    from importlib import metadata

    return metadata.version("tinyvdb")


def _transform(source: str, field: str, transform: dict) -> tuple[np.ndarray, np.ndarray]:
    """(linear (3, 3), translation (3,)) of tinyvdb's transform dictionary; SceneError where it is not a
    finite invertible affine map."""
    kind = transform.get("type")
    if kind == "affine":
        matrix = np.array(transform["matrix"], dtype=np.float64)
        if matrix.shape != (4, 4) or not np.allclose(matrix[:, 3], (0.0, 0.0, 0.0, 1.0)):
            raise SceneError(source, field, "its affine transform is not affine (a projective last column)")
        linear, translation = matrix[:3, :3], matrix[3, :3]
    elif kind in ("scale_translate", "uniform_scale_translate", "scale", "uniform_scale", "translation"):
        scale = np.array(transform.get("scale", (1.0, 1.0, 1.0)), dtype=np.float64)
        linear = np.diag(np.ones(3) if kind == "translation" else scale)
        translation = np.array(transform.get("translation", (0.0, 0.0, 0.0)), dtype=np.float64)
    else:
        raise SceneError(source, field, f"its transform {kind!r} is not an affine map (a frustum cannot be imported)")
    if not (np.all(np.isfinite(linear)) and np.all(np.isfinite(translation))):
        raise SceneError(source, field, "its transform holds numbers that are not finite")
    if np.abs(linear).max() > MAX_MAGNITUDE or np.abs(translation).max() > MAX_MAGNITUDE:
        raise SceneError(source, field, f"its transform holds numbers past +-{MAX_MAGNITUDE:g}")
    singular = np.linalg.svd(linear, compute_uv=False)
    if not singular[-1] > MIN_RELATIVE_VOXEL * singular[0]:
        raise SceneError(source, field, "its transform is singular (a voxel of no volume)")
    return linear, translation


def write_density_grids(path, grids: list[DensityGrid]) -> None:
    """Write `grids` (each with a diagonal `linear`: voxels aligned with the axes) to the OpenVDB file at
    `path` atomically, as ZIP-compressed float grids."""
    import tinyvdb

    file = tinyvdb.from_bytes(_template(grids))
    file.read_grids()  # the templates tinyvdb rebuilds each grid from
    for index, grid in enumerate(grids):
        file.replace_grid_from_sparse(
            index,
            np.ascontiguousarray(grid.voxels, dtype=np.int32).tobytes(),
            np.ascontiguousarray(grid.density, dtype=np.float32).tobytes(),
            grid.name,
        )
    data = _named(file.to_bytes(compression=tinyvdb.COMPRESS_ZIP, level=6), grids)
    file.close()
    atomic_write(Path(path), lambda f: f.write(data))


def _named(data: bytes, grids: list[DensityGrid]) -> bytes:
    """tinyvdb's file with each grid's name and class in its metadata, where OpenVDB (Blender, Houdini) reads a
    grid's name: tinyvdb writes it in the grid's descriptor only, and drops the template's metadata."""
    out = bytearray()
    cursor = struct.calcsize("<qIIIB") + 36
    cursor += _skip_metadata(data, cursor)
    out += data[: cursor + 4]  # header, file metadata, grid count
    cursor += 4
    for grid in grids:
        descriptor_end = cursor
        for _ in range(3):  # unique name, type, instance parent
            descriptor_end += 4 + struct.unpack_from("<I", data, descriptor_end)[0]
        start, block, end = struct.unpack_from("<qqq", data, descriptor_end)
        flags_end = start + 4
        old_metadata = _skip_metadata(data, flags_end)
        metadata = _metadata([("class", "string", b"fog volume"), ("name", "string", grid.name.encode("utf-8"))])
        shift = len(out) + (descriptor_end + 24 - cursor) - start + len(metadata) - old_metadata
        out += data[cursor:descriptor_end]
        out += struct.pack("<qqq", len(out) + 24, block + shift, end + shift)
        out += data[start:flags_end] + metadata + data[flags_end + old_metadata : end]
        cursor = end
    return bytes(out)


def _skip_metadata(data: bytes, offset: int) -> int:
    """The length of the metadata block at `offset` (a count, then name, type and value, each sized)."""
    cursor = offset + 4
    for _ in range(struct.unpack_from("<i", data, offset)[0]):
        for _ in range(3):
            cursor += 4 + struct.unpack_from("<I", data, cursor)[0]
    return cursor - offset


def _template(grids: list[DensityGrid]) -> bytes:
    """An OpenVDB file of `grids`' descriptors and transforms, their trees empty (format of io::Archive)."""
    out = bytearray(struct.pack("<qIIIB", VDB_MAGIC, VDB_FILE_VERSION, 10, 0, 1) + str(uuid.uuid4()).encode())
    out += _metadata([("creator", "string", b"cloudview")])
    out += struct.pack("<i", len(grids))
    for grid in grids:
        scale = np.diag(grid.linear)
        if not np.array_equal(np.diag(scale), grid.linear):
            raise ValueError(f"grid {grid.name!r}: only grids aligned with the axes are written")
        out += _string(grid.name) + _string(FLOAT_TREE) + _string("")  # no instance parent
        positions = len(out)
        out += bytes(24)  # the grid's start, its buffers' start and its end, known once written
        start = len(out)
        out += struct.pack("<I", 0)  # the grid's compression flags: tinyvdb sets its own on saving
        out += _metadata([])  # tinyvdb drops a template grid's metadata when it rebuilds the grid: `_named`
        # ScaleTranslateMap: translation, scale, voxel size, 1 / scale, 1 / scale^2, 1 / (2 scale)
        values = (grid.translation, scale, scale, 1.0 / scale, 1.0 / scale**2, 0.5 / scale)
        out += _string("ScaleTranslateMap") + struct.pack("<18d", *np.concatenate(values))
        out += struct.pack("<i", 1) + struct.pack("<fII", 0.0, 0, 0)  # one buffer; root: background 0, empty
        out[positions : positions + 24] = struct.pack("<qqq", start, len(out), len(out))
    return bytes(out)


def _string(text: str) -> bytes:
    data = text.encode("utf-8")
    return struct.pack("<I", len(data)) + data


def _metadata(entries) -> bytes:
    out = struct.pack("<i", len(entries))
    for name, kind, data in entries:
        out += _string(name) + _string(kind) + struct.pack("<I", len(data)) + data
    return out
