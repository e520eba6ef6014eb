"""A scene's clouds as a medium: particle radii, extinction per metre and optical thickness, JSON out.

    python scripts/cloud_optics.py [cloudcore/resources/scenes/valley.toml] [--json out/cloud_optics.json]

The medium is the truth's (`cloudcore.measure.truth.medium_grids`, 3 voxels a median radius): the extinction at a
median particle's centre, the voxels' extinction where it is above 5% of the largest, and the optical depth along
a vertical line through each cloud's mean centre.  docs/shading.md ("Optical properties with physical meaning").
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cloudcore.light.illumination import cloud_optics
from cloudcore.measure.benchmark import write_report
from cloudcore.measure.truth import medium_grids, optical_depths, peak_extinction
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene

#: voxels counted as inside a cloud: extinction above this share of the largest
INSIDE_SHARE = 0.05


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    parser.add_argument("--json", type=Path, help="write the results here as well as to stdout")
    args = parser.parse_args()

    scene = load_scene(args.scene)
    radii = np.concatenate([cloud.radii for cloud in scene.clouds])
    tau = np.concatenate([cloud_optics(cloud, scene.shading)[0] for cloud in scene.clouds])
    peak = peak_extinction(tau, radii)
    grids = medium_grids(scene, 3.0)
    extinction = np.concatenate([grid.extinction.ravel() for grid in grids])
    inside = extinction[extinction > INSIDE_SHARE * extinction.max()]
    low = np.array([[*cloud.centres.mean(axis=0)] for cloud in scene.clouds])
    low[:, 1] = [cloud.centres[:, 1].min() - cloud.radii.max() for cloud in scene.clouds]
    up = np.tile([0.0, 1.0, 0.0], (len(low), 1))
    vertical = optical_depths(grids, low, up)[0]
    report = {
        "scene": args.scene,
        "radius_m": {
            "median": float(np.median(radii)),
            "p10": float(np.percentile(radii, 10)),
            "p90": float(np.percentile(radii, 90)),
        },
        "particle_centre_extinction_per_m": float(np.median(peak)),
        "inside_extinction_per_m": {
            "median": float(np.median(inside)),
            "mean": float(inside.mean()),
            "largest": float(extinction.max()),
        },
        "vertical_optical_depth_through_cloud_centres": {
            "median": float(np.median(vertical)),
            "min": float(vertical.min()),
            "max": float(vertical.max()),
        },
    }
    write_report(report, args.json)


if __name__ == "__main__":
    main()
