"""Wang's three flight scenarios (JGT 2004, section 6.3) and two skies of our own, as benchmark scenes.

Wang flew Flight Simulator 2004 through three weathers told apart by cloud-block overdraw (the summed sprite
areas over each 4 km ground block, `cloudcore.measure.overdraw.cloud_block_overdraw`): sparse (170%),
scattered (200%) and overcast (475%), at 1024x768.  `wang_scene` fills 16 km by 16 km with the artist presets
of each weather (`cloudcore.artist.cloudgen.preset_cloud`), cloud by cloud from a seed, until every block holds
clouds and their mean overdraw reaches Wang's figure; the eye flies at 120 m/s through the clouds' level (for the
overcast, up through the deck's base).

`own_scene` makes two skies the level of detail was never tuned on: a line of towering cumulus flown beside
at low level (`cumulus_line`: few clouds, many particles each, most of the screen), and a climb through a
layer of small cumulus (`popcorn_climb`: many small clouds, the eye passing up through their level).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from cloudcore.artist.cloudgen import cumulus, preset_cloud
from cloudcore.measure.overdraw import WANG_BLOCK_SIZE_M, cloud_block_overdraw, scene_block_overdraw_statistics
from cloudcore.scene import Camera, Cloud, Scene

#: Wang's scenarios: (cloud-block overdraw, presets with (their bases' height in metres, their scale), the
#: flight's (start, end) eye heights); the scattered sky's towers are half the preset's size, or each would
#: pass the scenario's overdraw in its block alone
SCENARIOS = {
    "sparse": (1.70, {"cumulus_humilis": (1000.0, 1.0)}, (1150.0, 1150.0)),
    "scattered": (2.00, {"cumulus_humilis": (1000.0, 1.0), "cumulus_congestus": (900.0, 0.5)}, (1150.0, 1150.0)),
    "overcast": (4.75, {"stratocumulus": (1300.0, 1.0), "stratus": (900.0, 1.0)}, (700.0, 1350.0)),
}
BLOCKS = 16  # the 16 km square's 4 km blocks, every one holding clouds
SIDE_M = 4 * WANG_BLOCK_SIZE_M
FRAMES_PER_S = 30.0
SPEED_M_S = 120.0


def wang_clouds(scenario: str, seed: int = 2004) -> tuple[Cloud, ...]:
    """The clouds of `scenario`: presets placed at random over `SIDE_M` square until the blocks' mean
    overdraw reaches the scenario's."""
    target, presets, _ = SCENARIOS[scenario]
    rng = np.random.default_rng(seed)
    clouds: list[Cloud] = []
    names = sorted(presets)
    overdraw: dict = {}  # block -> its overdraw so far, a cloud's added as it is placed
    while len(overdraw) < BLOCKS or sum(overdraw.values()) / len(overdraw) < target:
        preset = names[int(rng.integers(len(names)))]
        x, z = rng.uniform(-SIDE_M / 2, SIDE_M / 2 - 1.0, 2)
        base = (x, presets[preset][0] + rng.uniform(-60.0, 60.0), z)
        scale = presets[preset][1] * rng.uniform(0.8, 1.2)
        cloud = preset_cloud(preset, f"{scenario}_{len(clouds):03d}", base, scale, seed + len(clouds))
        for block, value in zip(*cloud_block_overdraw(cloud.centres, cloud.radii)):
            overdraw[tuple(block)] = overdraw.get(tuple(block), 0.0) + value
        clouds.append(cloud)
    return tuple(clouds)


def flight_views(frames: int, start_height: float, end_height: float) -> list:
    """(scene clock, camera) of `frames` frames flying along -z across the middle at `SPEED_M_S`, climbing from
    `start_height` to `end_height`, looking 2 km ahead."""
    views = []
    for frame in range(frames):
        t = frame / max(frames - 1, 1)
        z = SIDE_M / 4 - frame * SPEED_M_S / FRAMES_PER_S
        y = start_height + t * (end_height - start_height)
        views.append((frame / FRAMES_PER_S, Camera((150.0, y, z), (150.0, y + 0.02 * 2000.0, z - 2000.0), 60.0)))
    return views


def wang_scene(world: Scene, scenario: str) -> tuple[Scene, float]:
    """(`world` with the clouds of `scenario`, their cloud-block overdraw)."""
    clouds = wang_clouds(scenario)
    overdraw = scene_block_overdraw_statistics(clouds)["block_overdraw_mean"]
    return dataclasses.replace(world, clouds=clouds, objects=(), cloud_field=None), overdraw


def own_scene(world: Scene, name: str, frames: int) -> tuple[Scene, list]:
    """(`world` with the clouds of our own sky `name`, the views of its flight)."""
    rng = np.random.default_rng(17)
    if name == "cumulus_line":
        clouds = []
        for index, x in enumerate(np.arange(-9000.0, 9001.0, 600.0)):
            size = np.array([rng.uniform(700, 1100), rng.uniform(900, 1600), rng.uniform(700, 1100)])
            base = (x + rng.uniform(-150, 150), rng.uniform(850, 950), rng.uniform(-200, 200))
            particles = cumulus(base, size, 1800, 0.07 * size[[0, 2]].min(), 100 + index)
            clouds.append(Cloud(f"line_{index:02d}", particles))
        views = []
        for frame in range(frames):
            x = -3000.0 + frame * SPEED_M_S / FRAMES_PER_S
            eye = (x, 700.0, 2000.0)
            views.append((frame / FRAMES_PER_S, Camera(eye, (x + 1500.0, 1100.0, 0.0), 60.0)))
    elif name == "popcorn_climb":
        clouds = []
        for index in range(1500):
            size = np.array([rng.uniform(90, 220), rng.uniform(60, 140), rng.uniform(90, 220)])
            base = (rng.uniform(-6000, 6000), rng.uniform(1200, 1350), rng.uniform(-6000, 6000))
            particles = cumulus(base, size, 150, 0.13 * size[[0, 2]].min(), 5000 + index)
            clouds.append(Cloud(f"popcorn_{index:04d}", particles))
        views = []
        for frame in range(frames):  # up through the layer: 1,150 to 1,550 m, 80 m/s across
            along = frame * 80.0 / FRAMES_PER_S
            eye = (-1500.0 + along, 1150.0 + 400.0 * frame / max(frames - 1, 1), 1500.0 - along)
            views.append((frame / FRAMES_PER_S, Camera(eye, (eye[0] + 1500.0, eye[1] + 400.0, eye[2] - 1500.0), 60.0)))
    else:
        raise ValueError(f"no sky of our own called {name!r}")
    return dataclasses.replace(world, clouds=tuple(clouds), objects=(), cloud_field=None), views
