"""The on-disk cache of work that is slow to redo and cheap to keep (numpy arrays in one .npz per key).

`$XDG_CACHE_HOME/cloudview`, or `~/.cache/cloudview` where that is unset.  An entry's file name is the
hash of its key, and the key is also stored inside, so a hash collision, a file from another format
version or a truncated or corrupt file reads as a miss and is rebuilt, never as a wrong answer or a
crash.  Entries are written atomically (`cloudcore.model.particle_files.atomic_write`): a crash mid-write
leaves the old entry or none.

The package ships the entries nearly every scene needs (`cloudcore/resources/cache`, laid out as the
cache is; `scripts/make_cache_entries.py` writes them), read before the user's cache: a fresh install
never spends a minute building them.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from pathlib import Path

import numpy as np

from cloudcore.model.particle_files import atomic_write
from cloudcore.resources import resource_path

_KEY_FIELD = "__cache_key__"


def cache_directory() -> Path:
    """Where cloudview keeps its cache: the XDG base directory's choice."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "cloudview"


def shipped_directory() -> Path:
    """The entries that ship with the package, read-only."""
    return resource_path("cache")


def entry_path(kind: str, key: dict, directory: Path | None = None) -> Path:
    """The file of `key` (a JSON-able dict naming every parameter the entry depends on) of `kind`, in
    `directory` (the user's cache by default)."""
    digest = hashlib.sha256(_canonical(key).encode()).hexdigest()[:24]
    return (cache_directory() if directory is None else directory) / kind / f"{digest}.npz"


def load_or_build(kind: str, key: dict, build) -> tuple[dict[str, np.ndarray], bool]:
    """(the arrays of `key`, whether they came from the cache): read them, or `build()` them and store them.

    `build` returns a dict of numpy arrays.  A cache that cannot be written (a read-only home) costs the
    rebuild next time, not the result now.
    """
    held = load(kind, key)
    if held is not None:
        return held, True
    arrays = build()
    try:
        store(kind, key, arrays)
    except OSError:
        pass
    return arrays, False


def load(kind: str, key: dict) -> dict[str, np.ndarray] | None:
    """The arrays of `key`, shipped or in the user's cache; None where neither holds them."""
    for directory in (shipped_directory(), cache_directory()):
        held = _read(entry_path(kind, key, directory), key)
        if held is not None:
            return held
    return None


def store(kind: str, key: dict, arrays: dict[str, np.ndarray], directory: Path | None = None) -> Path:
    """Write the entry `key` of `kind` (atomically) into `directory` (the user's cache by default)."""
    path = entry_path(kind, key, directory)

    def write(file):
        np.savez(file, **arrays, **{_KEY_FIELD: np.array(_canonical(key))})

    atomic_write(path, write)
    return path


def _read(path: Path, key: dict) -> dict[str, np.ndarray] | None:
    try:
        with np.load(path, allow_pickle=False) as held:
            if str(held[_KEY_FIELD]) != _canonical(key):
                return None
            return {name: held[name] for name in held.files if name != _KEY_FIELD}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None


def _canonical(key: dict) -> str:
    return json.dumps(key, sort_keys=True, separators=(",", ":"))
