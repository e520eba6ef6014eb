"""Regenerate cloudcore/resources/scenes/aircraft_in_cloud.toml: one cumulus, an aircraft flying through it.

    python scripts/make_aircraft_scene.py [--out cloudcore/resources/scenes/aircraft_in_cloud.toml]

The scene of the split-layer tests and docs (Harris 3.1.1): the aircraft
crosses the cloud at 45 degrees to the fixed camera's view, so an impostor
quad through the cloud's centre would cut through its fuselage.  The
particles are shipped as .npy beside the scene, like the default scene's.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cloudcore.artist.cloudgen import cumulus
from cloudcore.model.scene import Camera, CameraPath, Cloud, Lighting, Scene, SceneObject, Shading, View
from cloudcore.scenes.files import save_scene

SEED = 311
CLOUD_BASE = np.array([0.0, 1000.0, 0.0])
CLOUD_SIZE = (520.0, 320.0, 520.0)
#: thin enough that the aircraft shows through the particles in front of it
THIN_OPTICAL_DEPTH = 3.0


def build() -> Scene:
    cloud = Cloud(
        "cumulus", cumulus(CLOUD_BASE, CLOUD_SIZE, 1400, 0.085 * CLOUD_SIZE[0], SEED), optical_depth=THIN_OPTICAL_DEPTH
    )
    heart = cloud.centres.mean(axis=0)
    # straight through the heart, 45 degrees across the camera's view, 60 m/s
    across = np.array([1.0, 0.0, -1.0]) / np.sqrt(2.0)
    path = np.array([[t, *(heart + across * 60.0 * (t - 10.0) + [0.0, 40.0, 150.0])] for t in (0.0, 10.0, 20.0)])
    eye = heart + [120.0, 60.0, 620.0]
    orbit = np.array(
        [
            [t, *(heart + 650.0 * np.array([np.sin(a), 0.15, np.cos(a)])), *heart]
            for t, a in zip(np.linspace(0.0, 20.0, 9), np.linspace(0.0, 2.0 * np.pi, 9))
        ]
    )
    return Scene(
        camera=Camera(tuple(eye), tuple(heart), 45.0),
        lighting=Lighting(time_of_day=15.5),
        shading=Shading(),
        clouds=(cloud,),
        objects=(SceneObject("aircraft", primitive="aircraft", scale=70.0, path=path),),
        camera_paths=(CameraPath("orbit", orbit),),
        # named views for `cloudview check` (docs/screenshot-tests.md): the cloud at sunset; the aircraft in its
        # heart at 10 s, the cloud split in layers around it; and from the side a quarter of the way round the
        # orbit, in auto mode as the editor draws it
        views=(
            View("sunset", time_of_day=18.6),
            View("aircraft_inside", time_s=10.0),
            View("orbit_quarter", camera_path="orbit", t=5.0, mode="auto"),
        ),
        description=f"An aircraft flying through one cumulus (split-layer tests); "
        f"scripts/make_aircraft_scene.py, seed {SEED}.",
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("cloudcore/resources/scenes/aircraft_in_cloud.toml"))
    out = parser.parse_args().out
    save_scene(build(), out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
