"""Write the cache entries cloudview ships (cloudcore/resources/cache), so a fresh install builds none of them.

    python scripts/make_cache_entries.py

Yusov's reference-particle tables (`cloudcore.light.precomputed`) for the phase functions of every
shipped scene, at the default resolution: a minute each to build on two cores; and the atmosphere's
transmittance and multiple-scattering tables (`cloudcore.atmosphere.sky`) for the air of every shipped
scene, 2-3 s each.  Run it when `precomputed.FORMAT_VERSION`, `sky.FORMAT_VERSION` or the tables'
computation changes (an entry of an older key is then ignored, so nothing wrong is read meanwhile, only
slower), and commit what it writes.
"""

from __future__ import annotations

import functools
import time

from cloudcore.atmosphere import sky
from cloudcore.light.lighting import atmosphere_parameters
from cloudcore.light.precomputed import CACHE_KIND, TableResolution, build_tables, cache_key
from cloudcore.resources import resource_path
from cloudcore.runtime import disk_cache
from cloudcore.scenes.files import load_scene


def shipped_scenes():
    return [load_scene(path) for path in sorted(resource_path("scenes").glob("*.toml"))]


def shipped_phases() -> list[tuple[str, float]]:
    """The (phase, g) of every shipped scene, Rayleigh's g taken as 0 (it ignores it)."""
    phases = {(s.shading.phase, 0.0 if s.shading.phase == "rayleigh" else s.shading.g) for s in shipped_scenes()}
    return sorted(phases)


def shipped_airs() -> list:
    """The atmosphere parameters of every shipped scene whose sky is physical."""
    airs = {atmosphere_parameters(s.lighting.air) for s in shipped_scenes() if s.lighting.air.sky == "physical"}
    return sorted(airs, key=repr)


def write(kind: str, key: dict, build, directory) -> None:
    start = time.perf_counter()
    path = disk_cache.store(kind, key, build(), directory)
    print(f"{path.relative_to(directory.parent)} ({path.stat().st_size} bytes, {time.perf_counter() - start:.1f} s)")


def main() -> None:
    directory = disk_cache.shipped_directory()
    for kind in (CACHE_KIND, sky.CACHE_KIND):
        for stale in directory.glob(f"{kind}/*.npz"):
            stale.unlink()
    for phase, g in shipped_phases():
        print(f"{phase} g={g}: ", end="")
        write(CACHE_KIND, cache_key(phase, g), functools.partial(build_tables, phase, g, TableResolution()), directory)
    for params in shipped_airs():
        print("atmosphere: ", end="")
        write(sky.CACHE_KIND, sky.cache_key(params), functools.partial(sky.build_tables, params), directory)


if __name__ == "__main__":
    main()
