"""How far Yusov's reference-particle tables are from tables built finer: the error that chose their resolution.

    .venv/bin/python scripts/precomputed_table_resolution.py --json out/precomputed_resolution.json

Builds the tables at a coarser, the default and a finer resolution (`cloudcore.light.precomputed`,
no cache) and compares what the eye pass reads, the colour factor p(mu) a single(mu) + multiple(mu)
and the ambient response, at albedo 0.9 and 1 over every tau node and mu, with the finest as reference:
the largest and the mean relative error, and the build time and size of each.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from cloudcore.light.phase import phase_function
from cloudcore.light.precomputed import ReferenceTables, TableResolution, build_tables

RESOLUTIONS = {
    "coarse": TableResolution(
        chord_impacts=33,
        chord_positions=33,
        volume_radii=24,
        volume_polar=24,
        volume_azimuths=16,
        voxels=16,
        direction_cosines=8,
        direction_azimuths=12,
    ),
    "default": TableResolution(),
    "fine": TableResolution(
        chord_impacts=129,
        chord_positions=129,
        volume_radii=96,
        volume_polar=96,
        volume_azimuths=48,
        voxels=32,
        direction_cosines=16,
        direction_azimuths=24,
        leaving_azimuths=8,
    ),
}


def eye_pass_terms(tables: ReferenceTables, albedo: float) -> tuple[np.ndarray, np.ndarray]:
    """(colour factor (taus, views), ambient response (taus,)) at `albedo` for every tau node."""
    taus = tables.optical_depths
    single, multiple, ambient = tables.scattering_profiles(taus, np.full(len(taus), albedo))
    phase = phase_function(tables.view_cosines, tables.phase, tables.g)
    return phase * single + multiple, ambient


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--phase", default="rayleigh")
    parser.add_argument("--g", type=float, default=0.0)
    parser.add_argument("--json", type=Path, help="write the report here as well")
    args = parser.parse_args(argv)
    built = {}
    for name, resolution in RESOLUTIONS.items():
        start = time.perf_counter()
        arrays = build_tables(args.phase, args.g, resolution)
        seconds = time.perf_counter() - start
        built[name] = (ReferenceTables(**arrays, phase=args.phase, g=args.g), seconds)
    reference = built["fine"][0]
    report = {"phase": args.phase, "g": args.g, "tables": {}}
    for name, (tables, seconds) in built.items():
        resolution = dataclasses.asdict(RESOLUTIONS[name])
        entry = {"build_s": round(seconds, 2), "bytes": tables.nbytes, "resolution": resolution}
        for albedo in (0.9, 1.0):
            colour, ambient = eye_pass_terms(tables, albedo)
            true_colour, true_ambient = eye_pass_terms(reference, albedo)
            relative = np.abs(colour - true_colour) / np.abs(true_colour).max(axis=1, keepdims=True)
            entry[f"albedo_{albedo}"] = {
                "colour_max_relative_error": float(relative.max()),
                "colour_mean_relative_error": float(relative.mean()),
                "ambient_max_relative_error": float(np.max(np.abs(ambient - true_ambient) / true_ambient)),
                "ambient_response": [round(float(a), 4) for a in ambient],
            }
        report["tables"][name] = entry
    text = json.dumps(report, indent=2)
    print(text)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(text)


if __name__ == "__main__":
    main()
