"""Regenerate cloudcore/resources/scenes/formation.toml: one cloud forming, one dissipating, one steady between them.

    python scripts/make_formation_scene.py [--out cloudcore/resources/scenes/formation.toml]
    cloudview record cloudcore/resources/scenes/formation.toml --camera-path watch --out formation.mp4

The demo of Wang's formation and dissipation (2004, section 4 and Listing 1):
over the 10 s camera path `watch` the left cloud grows from its core outward
and the right one thins from its edges until it is gone; the steady middle
one shows the formation factor is per cloud.  The animations overlap in
the middle of the path, both are done before its end, and every cloud stays
inside the ring radius so each is drawn as itself.  The particles come from
`cloudcore.artist.cloudgen.preset_cloud` and are shipped as .npy beside the scene.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from cloudcore.artist.cloudgen import preset_cloud
from cloudcore.model.cloud_records import Formation
from cloudcore.model.scene import Camera, CameraPath, Lighting, Scene, Shading, Terrain
from cloudcore.scenes.files import save_scene

SEED = 2004
CLOUD_BASE_Y = 1000.0
#: metres between the clouds' centres along x: their 900 m widths never touch
SPACING = 1100.0
WATCH_S = 10.0
FORMING = Formation("form", start_s=1.0, duration_s=6.0)
DISSIPATING = Formation("dissipate", start_s=3.0, duration_s=6.0)


def build() -> Scene:
    def humilis(name: str, x: float, seed: int, formation: Formation | None):
        cloud = preset_cloud("cumulus_humilis", name, (x, CLOUD_BASE_Y, 0.0), seed=seed)
        return dataclasses.replace(cloud, formation=formation)

    clouds = (
        humilis("forming", -SPACING, SEED, FORMING),
        humilis("steady", 0.0, SEED + 1, None),
        humilis("dissipating", SPACING, SEED + 2, DISSIPATING),
    )
    middle = (0.0, CLOUD_BASE_Y + 250.0, 0.0)
    # a slow dolly in from just below the cloud base, so the clouds stand against the sky, all three in view
    watch = np.array(
        [[0.0, 0.0, CLOUD_BASE_Y - 100.0, 2800.0, *middle], [WATCH_S, 0.0, CLOUD_BASE_Y - 100.0, 2300.0, *middle]]
    )
    return Scene(
        camera=Camera(tuple(watch[0, 1:4]), middle, 60.0),
        lighting=Lighting(time_of_day=15.5),
        shading=Shading(),
        clouds=clouds,
        terrain=Terrain(size=(12000.0, 12000.0), height=500.0),
        camera_paths=(CameraPath("watch", watch),),
        description=f"Cloud formation and dissipation (Wang 2004, Listing 1): left forms from 1 s to 7 s, "
        f"right dissipates from 3 s to 9 s, middle steady; scripts/make_formation_scene.py, "
        f"seed {SEED}.",
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("cloudcore/resources/scenes/formation.toml"))
    out = parser.parse_args().out
    save_scene(build(), out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
