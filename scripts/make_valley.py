"""Regenerate the default scene cloudcore/resources/scenes/valley.toml (after Harris 2002, figure 3).

    python scripts/make_valley.py [--out cloudcore/resources/scenes/valley.toml]

34 cumulus clouds (about 90,000 particles) hang low over a procedural valley
of 59,858 triangles, lit by an afternoon sun; a 30 s camera path `flythrough`
passes through two clouds, the first while an aircraft crosses it.  Everything follows
from SEED; the particles are shipped as .npy beside the scene so the golden
images never depend on numpy's random streams.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from cloudcore.artist.cloudgen import cumulus
from cloudcore.model.scene import Camera, CameraPath, Cloud, Lighting, Scene, SceneObject, Shading, Terrain
from cloudcore.scenes.files import save_scene

SEED = 2002
CLOUD_COUNT = 34
TARGET_PARTICLES = 90_000


def place_clouds(rng) -> list[tuple[np.ndarray, np.ndarray]]:
    """(base centre, size) of each cloud, spread without overlaps over the valley."""
    placed: list[tuple[np.ndarray, np.ndarray]] = []
    while len(placed) < CLOUD_COUNT:
        size = np.array([rng.uniform(380, 760), rng.uniform(200, 380), rng.uniform(380, 760)])
        centre = np.array([rng.uniform(-2300, 2300), rng.uniform(820, 1050), rng.uniform(-2700, 2500)])
        if all(np.linalg.norm((centre - c)[[0, 2]]) > 0.5 * (size[0] + s[0]) * 0.9 for c, s in placed):
            placed.append((centre, size))
    return placed


def build() -> Scene:
    rng = np.random.default_rng(SEED)
    placed = place_clouds(rng)
    volumes = np.array([np.prod(s) for _, s in placed])
    counts = np.maximum(200, np.round(TARGET_PARTICLES * volumes / volumes.sum())).astype(int)
    clouds = tuple(
        Cloud(f"cumulus_{i:02d}", cumulus(c, s, int(n), 0.085 * min(s[0], s[2]), SEED + i))
        for i, ((c, s), n) in enumerate(zip(placed, counts))
    )

    def heart(cloud: Cloud) -> np.ndarray:
        return cloud.centres.mean(axis=0)

    # The flythrough enters the cloud nearest the start, then one further up the valley.
    start = np.array([0.0, 700.0, 3000.0])
    by_distance = sorted(clouds, key=lambda c: np.linalg.norm(heart(c)[[0, 2]] - start[[0, 2]]))
    first = heart(by_distance[0])
    second = min(
        (c for c in clouds if heart(c)[2] < first[2] - 1500),
        key=lambda c: abs(heart(c)[0] - first[0]) + abs(heart(c)[2] - first[2] + 2200),
    )
    second = heart(second)
    exit_point = second + (second - first) / np.linalg.norm(second - first) * 1600 + [0, 250, 0]
    stations = [
        (0.0, start),
        (9.0, first),
        (14.0, 0.5 * (first + second) + [0, 120, 0]),
        (19.0, second),
        (30.0, exit_point),
    ]
    keys = []
    for i, (t, position) in enumerate(stations):
        ahead = stations[min(i + 1, len(stations) - 1)][1]
        if i == len(stations) - 1:
            ahead = position + (position - stations[i - 1][1])
        keys.append([t, *position, *ahead])

    # The aircraft crosses the first cloud, right to left across the camera's view, at its heart at t = 6 s,
    # while the camera closes in (so the split layers show along the flythrough).
    across = np.cross(first - start, [0.0, 1.0, 0.0])
    across[1] = 0.0
    across /= np.linalg.norm(across)
    aircraft_path = np.array(
        [[t, *(first + across * 70.0 * (t - 6.0) + [0.0, 30.0 * np.sin(t / 6.0), 0.0])] for t in np.linspace(0, 30, 7)]
    )
    return Scene(
        # an establishing view up the valley; the flythrough has its own keys
        camera=Camera((450.0, 330.0, 2900.0), (-250.0, 850.0, -600.0), 60.0),
        lighting=Lighting(time_of_day=15.5),
        shading=Shading(),
        clouds=clouds,
        terrain=Terrain(kind="heightfield", size=(6000.0, 6000.0), resolution=174, height=650.0, seed=7),
        objects=(SceneObject("aircraft", primitive="aircraft", scale=40.0, path=aircraft_path),),
        camera_paths=(CameraPath("flythrough", np.array(keys)),),
        description=f"Default scene: cumulus over a valley after Harris 2002 fig. 3; "
        f"scripts/make_valley.py, seed {SEED}.",
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("cloudcore/resources/scenes/valley.toml"))
    out = parser.parse_args().out
    scene = save_scene(build(), out)
    print(f"wrote {out}: {len(scene.clouds)} clouds, {scene.particle_count} particles")


if __name__ == "__main__":
    main()
