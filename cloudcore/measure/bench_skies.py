"""The skies the benchmark suite flies that no scene file holds: made here from a seed, each over a world scene
(its terrain, lighting and sky), so that a case names them as data (`cloudcore.cli.bench_suite`).

- Harris's scaling test (GDC 2002, section 4, figure 8): 100 to 12,800 clouds of 200 particles each, the eye
  moving on a circle, then straight through the clouds in its view direction (`harris_scene`, `circle_views`,
  `through_views`).
- Wang's three flight scenarios (JGT 2004, section 6.3), told apart by cloud-block overdraw (`wang_scene`,
  `wang_flight_views`).
- Skies of our own the level of detail was never tuned on: a line of towering cumulus and a climb through
  popcorn cumulus (`own_scene`, `own_views`), a field of cumulus of another density and a stratocumulus deck
  (`untuned_scene`), and a field of a million particles and more (`particle_field`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from cloudcore.artist.cloudgen import cumulus, preset_cloud
from cloudcore.model.scene import Camera, CameraPath, Cloud, Scene
from cloudcore.stats.overdraw import WANG_BLOCK_SIZE_M, cloud_block_overdraw

FRAMES_PER_S = 30.0

# Harris's figure 8.  Harris gives the counts and the two motions, not the layout; here the clouds are small
# cumulus (`cloudcore.artist.cloudgen.cumulus`, 160 to 320 m across) on a jittered square grid `HARRIS_SPACING_M`
# apart between 850 and 1,150 m up, so the field grows with the count at a constant density, as a world filled
# with more sky would.  The eye flies at the clouds' height at `HARRIS_SPEED_M_S` (a light aircraft), 30 frames a
# second: on the circle (radius `HARRIS_CIRCLE_RADIUS_M` round the field's centre) looking along its way, or
# through the field's middle along +x.  Nothing here was tuned on the level of detail: the sizes are Harris's, the
# rest a plausible sky.
HARRIS_COUNTS = (100, 200, 400, 800, 1600, 3200, 6400, 12800)
HARRIS_PARTICLES_PER_CLOUD = 200
HARRIS_SPACING_M = 700.0
HARRIS_CIRCLE_RADIUS_M = 1500.0
HARRIS_SPEED_M_S = 60.0
HARRIS_CLOUD_HEIGHT_M = 1000.0


def harris_clouds(count: int, seed: int = 2002) -> tuple[Cloud, ...]:
    """`count` cumulus of `HARRIS_PARTICLES_PER_CLOUD` particles on a jittered grid centred on the origin."""
    rng = np.random.default_rng(seed)
    side = math.ceil(math.sqrt(count))
    clouds = []
    for index in range(count):
        row, column = divmod(index, side)
        base = np.array(
            [
                (column - (side - 1) / 2 + rng.uniform(-0.3, 0.3)) * HARRIS_SPACING_M,
                HARRIS_CLOUD_HEIGHT_M + rng.uniform(-150.0, 150.0),
                (row - (side - 1) / 2 + rng.uniform(-0.3, 0.3)) * HARRIS_SPACING_M,
            ]
        )
        size = np.array([rng.uniform(160, 320), rng.uniform(90, 180), rng.uniform(160, 320)])
        particles = cumulus(base, size, HARRIS_PARTICLES_PER_CLOUD, 0.12 * size[[0, 2]].min(), seed + index)
        clouds.append(Cloud(f"harris_{index:05d}", particles))
    return tuple(clouds)


def harris_scene(world: Scene, count: int) -> Scene:
    """`world` (its terrain, lighting and sky) with `count` of Harris's clouds and no objects."""
    return dataclasses.replace(world, clouds=harris_clouds(count), objects=(), camera=circle_views(1)[0][1])


def circle_views(frames: int) -> list:
    """(scene clock, camera) of `frames` frames on the circle round the field's centre, looking along the way."""
    step = HARRIS_SPEED_M_S / FRAMES_PER_S / HARRIS_CIRCLE_RADIUS_M  # radians a frame
    views = []
    for frame in range(frames):
        angle = frame * step
        eye = (
            HARRIS_CIRCLE_RADIUS_M * math.cos(angle),
            HARRIS_CLOUD_HEIGHT_M,
            HARRIS_CIRCLE_RADIUS_M * math.sin(angle),
        )
        ahead = (-math.sin(angle), 0.0, math.cos(angle))
        look_at = tuple(e + 1000.0 * a for e, a in zip(eye, ahead))
        views.append((frame / FRAMES_PER_S, Camera(eye, look_at, 60.0)))
    return views


def through_views(frames: int) -> list:
    """(scene clock, camera) of `frames` frames flying along +x through the field's middle, looking ahead."""
    start = -0.5 * HARRIS_SPEED_M_S / FRAMES_PER_S * frames
    height = HARRIS_CLOUD_HEIGHT_M + 20.0
    views = []
    for frame in range(frames):
        x = start + frame * HARRIS_SPEED_M_S / FRAMES_PER_S
        eye = (x, height, 0.5 * HARRIS_SPACING_M)
        views.append((frame / FRAMES_PER_S, Camera(eye, (x + 1000.0, height, 0.5 * HARRIS_SPACING_M), 60.0)))
    return views


# Wang's scenarios.  Wang flew Flight Simulator 2004 through three weathers told apart by cloud-block overdraw
# (the summed sprite areas over each 4 km ground block, `cloudcore.stats.overdraw.cloud_block_overdraw`): sparse
# (170%), scattered (200%) and overcast (475%), at 1024x768.  `wang_scene` fills 16 km by 16 km with the artist
# presets of each weather (`cloudcore.artist.cloudgen.preset_cloud`), cloud by cloud from a seed, until every
# block holds clouds and their mean overdraw reaches Wang's figure; the eye flies at 120 m/s through the clouds'
# level (for the overcast, up through the deck's base).

#: Wang's scenarios: (cloud-block overdraw, presets with (their bases' height in metres, their scale), the
#: flight's (start, end) eye heights); the scattered sky's towers are half the preset's size, or each would
#: pass the scenario's overdraw in its block alone
WANG_SCENARIOS = {
    "sparse": (1.70, {"cumulus_humilis": (1000.0, 1.0)}, (1150.0, 1150.0)),
    "scattered": (2.00, {"cumulus_humilis": (1000.0, 1.0), "cumulus_congestus": (900.0, 0.5)}, (1150.0, 1150.0)),
    "overcast": (4.75, {"stratocumulus": (1300.0, 1.0), "stratus": (900.0, 1.0)}, (700.0, 1350.0)),
}
WANG_BLOCKS = 16  # the 16 km square's 4 km blocks, every one holding clouds
WANG_SIDE_M = 4 * WANG_BLOCK_SIZE_M
WANG_SPEED_M_S = 120.0


def wang_clouds(scenario: str, seed: int = 2004) -> tuple[Cloud, ...]:
    """The clouds of `scenario`: presets placed at random over `WANG_SIDE_M` square until the blocks' mean
    overdraw reaches the scenario's."""
    target, presets, _ = WANG_SCENARIOS[scenario]
    rng = np.random.default_rng(seed)
    clouds: list[Cloud] = []
    names = sorted(presets)
    overdraw: dict = {}  # block -> its overdraw so far, a cloud's added as it is placed
    while len(overdraw) < WANG_BLOCKS or sum(overdraw.values()) / len(overdraw) < target:
        preset = names[int(rng.integers(len(names)))]
        x, z = rng.uniform(-WANG_SIDE_M / 2, WANG_SIDE_M / 2 - 1.0, 2)
        base = (x, presets[preset][0] + rng.uniform(-60.0, 60.0), z)
        scale = presets[preset][1] * rng.uniform(0.8, 1.2)
        cloud = preset_cloud(preset, f"{scenario}_{len(clouds):03d}", base, scale, seed + len(clouds))
        for block, value in zip(*cloud_block_overdraw(cloud.centres, cloud.radii)):
            overdraw[tuple(block)] = overdraw.get(tuple(block), 0.0) + value
        clouds.append(cloud)
    return tuple(clouds)


def wang_flight_views(scenario: str, frames: int) -> list:
    """(scene clock, camera) of `frames` frames flying along -z across the middle at `WANG_SPEED_M_S`, climbing
    from the scenario's start height to its end height, looking 2 km ahead."""
    start_height, end_height = WANG_SCENARIOS[scenario][2]
    views = []
    for frame in range(frames):
        t = frame / max(frames - 1, 1)
        z = WANG_SIDE_M / 4 - frame * WANG_SPEED_M_S / FRAMES_PER_S
        y = start_height + t * (end_height - start_height)
        views.append((frame / FRAMES_PER_S, Camera((150.0, y, z), (150.0, y + 0.02 * 2000.0, z - 2000.0), 60.0)))
    return views


def wang_scene(world: Scene, scenario: str) -> Scene:
    """`world` with the clouds of `scenario`."""
    return dataclasses.replace(world, clouds=wang_clouds(scenario), objects=(), cloud_field=None)


# Skies of our own: a line of towering cumulus flown beside at low level (`cumulus_line`: few clouds, many
# particles each, most of the screen), and a climb through a layer of small cumulus (`popcorn_climb`: many small
# clouds, the eye passing up through their level).
OWN_SKIES = ("cumulus_line", "popcorn_climb")


def own_scene(world: Scene, name: str) -> Scene:
    """`world` with the clouds of our own sky `name` (one of `OWN_SKIES`)."""
    rng = np.random.default_rng(17)
    clouds = []
    if name == "cumulus_line":
        for index, x in enumerate(np.arange(-9000.0, 9001.0, 600.0)):
            size = np.array([rng.uniform(700, 1100), rng.uniform(900, 1600), rng.uniform(700, 1100)])
            base = (x + rng.uniform(-150, 150), rng.uniform(850, 950), rng.uniform(-200, 200))
            particles = cumulus(base, size, 1800, 0.07 * size[[0, 2]].min(), 100 + index)
            clouds.append(Cloud(f"line_{index:02d}", particles))
    elif name == "popcorn_climb":
        for index in range(1500):
            size = np.array([rng.uniform(90, 220), rng.uniform(60, 140), rng.uniform(90, 220)])
            base = (rng.uniform(-6000, 6000), rng.uniform(1200, 1350), rng.uniform(-6000, 6000))
            particles = cumulus(base, size, 150, 0.13 * size[[0, 2]].min(), 5000 + index)
            clouds.append(Cloud(f"popcorn_{index:04d}", particles))
    else:
        raise ValueError(f"no sky of our own called {name!r}")
    return dataclasses.replace(world, clouds=tuple(clouds), objects=(), cloud_field=None)


def own_views(name: str, frames: int) -> list:
    """(scene clock, camera) of the `frames` frames of the flight of our own sky `name`."""
    views = []
    for frame in range(frames):
        if name == "cumulus_line":  # beside the line, low, looking up at it
            x = -3000.0 + frame * WANG_SPEED_M_S / FRAMES_PER_S
            views.append((frame / FRAMES_PER_S, Camera((x, 700.0, 2000.0), (x + 1500.0, 1100.0, 0.0), 60.0)))
        elif name == "popcorn_climb":  # up through the layer: 1,150 to 1,550 m, 80 m/s across
            along = frame * 80.0 / FRAMES_PER_S
            eye = (-1500.0 + along, 1150.0 + 400.0 * frame / max(frames - 1, 1), 1500.0 - along)
            views.append((frame / FRAMES_PER_S, Camera(eye, (eye[0] + 1500.0, eye[1] + 400.0, eye[2] - 1500.0), 60.0)))
        else:
            raise ValueError(f"no sky of our own called {name!r}")
    return views


#: metres between neighbouring clouds of `particle_field` (the valley's clouds are 380 to 760 m across)
PARTICLE_FIELD_SPACING_M = 900.0


def particle_field(total: int, per_cloud: int, seed: int = 9) -> tuple[Cloud, ...]:
    """`total` particles in cumulus clouds of `per_cloud` each, on a jittered square grid ahead of the
    default camera (it looks along -z from z = 3000 m)."""
    rng = np.random.default_rng(seed)
    count = math.ceil(total / per_cloud)
    side = math.ceil(math.sqrt(count))
    clouds = []
    for index in range(count):
        row, column = divmod(index, side)
        base = np.array(
            [
                (column - (side - 1) / 2) * PARTICLE_FIELD_SPACING_M,
                rng.uniform(820.0, 1050.0),
                1500.0 - row * PARTICLE_FIELD_SPACING_M,
            ]
        )
        base[[0, 2]] += rng.uniform(-0.2, 0.2, 2) * PARTICLE_FIELD_SPACING_M
        size = np.array([rng.uniform(380, 760), rng.uniform(200, 380), rng.uniform(380, 760)])
        particles = min(per_cloud, total - index * per_cloud)
        clouds.append(
            Cloud(f"cumulus_{index:03d}", cumulus(base, size, particles, 0.085 * size[[0, 2]].min(), seed + index))
        )
    return tuple(clouds)


def straight_flight(name: str, start, end, look_ahead_m: float = 2000.0, speed_m_s: float = 120.0) -> CameraPath:
    """A straight, level-looking flight from `start` to `end` at `speed_m_s`, looking `look_ahead_m` ahead."""
    start, end = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    direction = (end - start) / np.linalg.norm(end - start)
    duration = float(np.linalg.norm(end - start)) / speed_m_s
    keys = [
        [t * duration, *(start + t * (end - start)), *(start + t * (end - start) + look_ahead_m * direction)]
        for t in np.linspace(0.0, 1.0, 5)
    ]
    return CameraPath(name, np.array(keys))


#: the two scenes the level of detail was never tuned on, each with the camera path it is flown along
UNTUNED_SCENES = {"cumulus_field": "through", "stratocumulus_deck": "under_and_into"}


def untuned_scene(world: Scene, name: str) -> Scene:
    """`world` with one of `UNTUNED_SCENES`' clouds, no objects, and its flight as its only camera path."""
    if name == "cumulus_field":
        return dataclasses.replace(
            world,
            clouds=particle_field(60_000, 1_500, seed=41),
            objects=(),
            camera_paths=(straight_flight("through", (-900.0, 950.0, 2200.0), (700.0, 980.0, -1400.0)),),
        )
    if name != "stratocumulus_deck":
        raise ValueError(f"no untuned scene called {name!r}")
    rng = np.random.default_rng(7)
    grid = [(x, z) for x in np.arange(-2400.0, 2401.0, 1200.0) for z in np.arange(-2400.0, 2401.0, 1200.0)]
    deck = tuple(
        preset_cloud(
            "stratocumulus",
            f"deck_{i:02d}",
            (x + rng.uniform(-150, 150), rng.uniform(1150.0, 1250.0), z + rng.uniform(-150, 150)),
            seed=i,
        )
        for i, (x, z) in enumerate(grid)
    )
    return dataclasses.replace(
        world,
        clouds=deck,
        objects=(),
        camera_paths=(straight_flight("under_and_into", (2600.0, 900.0, 2600.0), (-1800.0, 1200.0, -1800.0)),),
    )
