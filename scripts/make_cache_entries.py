"""Write the cache entries cloudview ships (cloudcore/resources/cache), so a fresh install builds none of them.

    python scripts/make_cache_entries.py

Yusov's reference-particle tables (`cloudcore.light.precomputed`) for the phase functions of every
shipped scene, at the default resolution: a minute each to build on two cores.  Run it when
`precomputed.FORMAT_VERSION` or the tables' computation changes (an entry of an older key is then
ignored, so nothing wrong is read meanwhile, only slower), and commit what it writes.
"""

from __future__ import annotations

import time

from cloudcore import disk_cache
from cloudcore.light.precomputed import CACHE_KIND, TableResolution, build_tables, cache_key
from cloudcore.resources import resource_path
from cloudcore.scenefile import load_scene


def shipped_phases() -> list[tuple[str, float]]:
    """The (phase, g) of every shipped scene, Rayleigh's g taken as 0 (it ignores it)."""
    scenes = sorted(resource_path("scenes").glob("*.toml"))
    phases = {(s.shading.phase, 0.0 if s.shading.phase == "rayleigh" else s.shading.g) for s in map(load_scene, scenes)}
    return sorted(phases)


def main() -> None:
    directory = disk_cache.shipped_directory()
    for stale in directory.glob(f"{CACHE_KIND}/*.npz"):
        stale.unlink()
    for phase, g in shipped_phases():
        start = time.perf_counter()
        arrays = build_tables(phase, g, TableResolution())
        path = disk_cache.store(CACHE_KIND, cache_key(phase, g), arrays, directory)
        print(
            f"{phase} g={g}: {path.relative_to(directory.parent)} ({path.stat().st_size} bytes, "
            f"{time.perf_counter() - start:.0f} s)"
        )


if __name__ == "__main__":
    main()
