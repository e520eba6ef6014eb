"""Particle files beside a scene: large clouds' particles as .npy, written so that a crash loses nothing.

`save_scene` (`cloudcore.scenes.files`) stores each large cloud's particles
through `store_particles`, which never overwrites a file the current TOML may
still name; every write is `atomic_write` (a temporary file, fsync, rename).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np

from cloudcore.model.scene import Cloud


def particles_file_for(scene_path, cloud_name: str) -> str:
    """Where `save_scene` puts a large cloud's particles, relative to the scene file (when that file is free)."""
    # ASCII: a name's 64 characters (`limits.MAX_NAME_LENGTH`) stay 64 bytes of the file system's 255
    safe = "".join(ch if (ch.isascii() and ch.isalnum()) or ch in "-_" else "_" for ch in cloud_name)
    return f"{particles_folder(scene_path)}/{safe}.npy"


def particles_folder(scene_path) -> str:
    """The folder beside a scene that belongs to it: its saves write and delete particle files there only."""
    return f"{Path(scene_path).stem}.particles"


def store_particles(cloud: Cloud, path: Path) -> str:
    """The particles_file, relative to the scene at `path`, that holds `cloud`'s particles, written if need be.

    The cloud's own particles_file is kept when it holds exactly these particles,
    unless it lies in another scene's folder (that scene's saves may change or
    delete it: a scene saved under a new name, or a recovery copy, gets copies of
    its own).  Otherwise the particles go into this scene's folder, under the
    cloud's name or, where that file holds other particles the current TOML may
    still name, under a name with their digest.
    """
    particles = np.ascontiguousarray(cloud.particles, dtype=np.float64)
    own_folder, default = particles_folder(path), particles_file_for(path, cloud.name)
    digest = hashlib.sha256(particles.tobytes()).hexdigest()[:16]
    by_digest = f"{own_folder}/{Path(default).stem}-{digest}.npy"
    candidates = [default, by_digest]
    if cloud.particles_file is not None:
        parts = Path(cloud.particles_file).parts
        if not parts or parts[0] == own_folder or not parts[0].endswith(".particles"):
            candidates.insert(0, cloud.particles_file)
    for relative in candidates:
        if _holds(path.parent / relative, particles):
            return relative
    relative = by_digest if (path.parent / default).exists() else default
    atomic_write(path.parent / relative, lambda f: np.save(f, particles))
    return relative


def open_particle_array(file: Path) -> np.ndarray:
    """The array a .npy holds, memory-mapped (a header that claims more data than the file holds fails here
    instead of allocating it); ValueError where its header describes none numpy can map safely.

    The header is read and checked before numpy maps the file: a forged one of zero-byte items and a negative
    dimension ('V0', (-1,)) killed the process with SIGFPE inside numpy's memmap (found by the fuzz tests).
    Only versions 1.0 and 2.0 are read: numpy writes 3.0 only for field names outside latin-1, which a plain
    numeric array has none of.
    """
    readers = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
    with open(file, "rb") as stream:
        version = np.lib.format.read_magic(stream)
        if version not in readers:
            raise ValueError(f"version {version[0]}.{version[1]} holds no plain numeric array")
        shape, _, dtype = readers[version](stream)  # numpy's own header size limit, as np.load
    if dtype.itemsize == 0:
        raise ValueError(f"items of {dtype} hold no bytes")
    if any(side < 0 for side in shape):
        raise ValueError(f"a negative dimension in its shape {shape}")
    return np.load(file, mmap_mode="r", allow_pickle=False)


def _holds(file: Path, particles: np.ndarray) -> bool:
    """Whether `file` is a .npy of exactly `particles` (float64, bit for bit)."""
    try:
        stored = open_particle_array(file)
    except Exception:  # missing, unreadable or corrupt (np.load raises many kinds): it does not hold them
        return False
    return stored.dtype == np.float64 and stored.shape == particles.shape and np.array_equal(stored, particles)


def remove_unnamed_particle_files(path: Path, named: set) -> None:
    """After a save's commit: delete the .npy files in the scene's own folder its TOML no longer names, and
    the temporary files that saves of this scene killed mid-write left (`atomic_write` names them)."""
    folder = path.parent / particles_folder(path)
    named_files = {(path.parent / relative).resolve() for relative in named}
    for file in [*folder.glob("*.npy"), *folder.glob(".*.tmp"), *path.parent.glob(f".{path.name}.*.tmp")]:
        if file.resolve() not in named_files:
            file.unlink(missing_ok=True)


def atomic_write(path: Path, write) -> None:
    """Write through a temporary file in the same folder, fsync, then rename over `path`."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
