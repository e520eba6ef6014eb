"""Aerial perspective (`cloudcore.atmosphere.aerial_perspective`, `cloudcore.light.air_between`): the volume
against the march it tables, what the air does to a surface with distance, the world pass against its numpy
twin, and nothing but finite values at the extremes."""

import dataclasses
import time

import numpy as np
import pytest

from cloudcore.atmosphere import sky_view
from cloudcore.atmosphere.aerial_perspective import MAX_DISTANCE_M, build_aerial_perspective, volume_texels
from cloudcore.atmosphere.parameters import EARTH
from cloudcore.atmosphere.scattering import in_scattering
from cloudcore.atmosphere.sky import atmosphere_tables
from cloudcore.atmosphere.sky_view import eye_radius
from cloudcore.atmosphere.transmittance import optical_depth
from cloudcore.light.air_between import AIR_CELL_ANGLE, AIR_MAX_CELLS, air_between, air_cells
from cloudcore.light.lighting import PHYSICAL_EXPOSURE
from cloudcore.light.live_air import LiveAir
from cloudcore.light.sky_background import scene_sky
from cloudcore.maths.colour import srgb_encode
from cloudcore.measure.imagecompare import compare
from cloudcore.model.scene import Air, Camera, Light, Lighting, Scene, SceneObject, Terrain
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.scenes.files import load_scene
from cloudcore.world.camera import FAR_PLANE_M, NEAR_PLANE_M, camera_pose, pixel_rays
from cloudcore.world.sun import sun_direction
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH, VALLEY

TABLES = atmosphere_tables(EARTH)


def test_the_volume_s_transmittance_is_the_exponential_of_the_optical_depth():
    """At the texel centres, from 1 km up: each texel's transmittance against exp(-optical depth) of a fine
    march of the same ray (the volume's rays go on past the planet's ground at its density: only rays above
    the ground here)."""
    volume = build_aerial_perspective(TABLES, 1000.0, sun_direction(15.5))
    light_view_cosine, mu, distance = volume_texels()
    rising = mu >= 0.0
    r = eye_radius(EARTH, 1000.0)
    depth = optical_depth(EARTH, r, mu[rising][None, :], distance[:, None], samples=2000)
    expected = np.exp(-depth)
    got = volume.transmittance[:, rising, 0, :]
    assert np.abs(got - expected).max() < 2e-3
    # less light through the longer rays, but for the 16-sample march's own error (4e-4 at most, measured)
    assert np.all(np.diff(got, axis=0) <= 1e-3)


@pytest.mark.parametrize("hours", [15.5, 18.25, 6.5])
@pytest.mark.parametrize("altitude", [0.0, 1500.0, 10000.0])
def test_the_volume_reads_as_the_march_it_tables(hours, altitude):
    """Between its texels too: random directions and distances against `in_scattering` marched with 64
    samples, in the renderer's values.  Measured: in-scattered p99 <= 0.0032, transmittance p99 <= 0.0035."""
    rng = np.random.default_rng(7)
    sun = sun_direction(hours)
    volume = build_aerial_perspective(TABLES, altitude, sun)
    directions = rng.normal(size=(3000, 3))
    directions[:, 1] = np.abs(directions[:, 1]) * rng.choice([-0.15, 1.0], size=3000)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    distances = MAX_DISTANCE_M * rng.random(3000) ** 2
    r = eye_radius(EARTH, altitude)
    radiance, transmittance = in_scattering(
        EARTH, TABLES.transmittance, TABLES.multiple_scattering, r, directions[:, 1], sun[1], directions @ sun,
        distances, 64,
    )  # fmt: skip
    got_radiance, got_transmittance = volume.radiance_and_transmittance(directions, distances)
    radiance_error = np.pi * PHYSICAL_EXPOSURE * np.abs(got_radiance - radiance)
    assert np.percentile(radiance_error, 99) < 0.005 and radiance_error.max() < 0.05
    assert np.percentile(np.abs(got_transmittance - transmittance), 99) < 0.005


def test_a_far_surface_fades_into_the_horizon_and_a_near_one_keeps_its_colour():
    """A level surface's colour seen along the horizon from 2 m up, ever closer to the sky there with distance."""
    lighting = Lighting(time_of_day=15.5)
    sky = scene_sky(lighting)
    air = air_between(sky, (0.0, 2.0, 0.0))
    toward = np.array([np.sin(1.0), 0.0, np.cos(1.0)])
    horizon = sky.radiance(toward + [0.0, 0.002, 0.0], 1e-3)
    surface = np.array([0.1, 0.15, 0.05])
    distances = np.array([0.0, 10.0, 500.0, 2000.0, 8000.0, 32000.0, MAX_DISTANCE_M])
    seen = air.seen_through(np.broadcast_to(surface, (7, 3)), np.broadcast_to(toward, (7, 3)), distances)
    assert np.allclose(seen[0], surface, atol=1e-9)
    assert np.allclose(seen[1], surface, rtol=0.01)
    gap = np.linalg.norm(seen - horizon, axis=1)
    assert np.all(np.diff(gap) < 0.0)
    assert gap[-1] < 0.3 * gap[0]


def test_the_gradient_sky_draws_no_air():
    assert air_between(scene_sky(Lighting(air=Air(sky="gradient"))), (0.0, 100.0, 0.0)) is None


@pytest.mark.parametrize("eye_altitude", [0.0, 50000.0])
@pytest.mark.parametrize("hours", [15.5, 19.5, 0.0])
def test_the_air_is_finite_at_the_extremes(eye_altitude, hours):
    """The eye on the ground and 50 km up, the sun up, set and at midnight: finite, the light added not negative,
    the transmittance in [0, 1]."""
    air = air_between(scene_sky(Lighting(time_of_day=hours)), (0.0, eye_altitude, 0.0))
    for values in (air.in_scattered(), air.transmittance()):
        assert np.isfinite(values).all()
    assert air.in_scattered().min() >= 0.0
    assert 0.0 <= air.transmittance().min() and air.transmittance().max() <= 1.0 + 1e-12
    directions = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    seen = air.seen_through(np.ones((3, 3)), directions, np.array([0.0, 1e9, 30000.0]))
    assert np.isfinite(seen).all()


def rays_and_distances(camera: Camera, depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit rays (h, w, 3), distances (h, w)): each pixel's ray and the distance along it to the window `depth`
    (h, w) a frame of `camera` read back (its eye-space depth undone from the projection)."""
    ndc = 2.0 * depth - 1.0
    eye_depth = 2.0 * FAR_PLANE_M * NEAR_PLANE_M / (FAR_PLANE_M + NEAR_PLANE_M - ndc * (FAR_PLANE_M - NEAR_PLANE_M))
    rays = pixel_rays(camera, RENDER_WIDTH, RENDER_HEIGHT)
    return rays, eye_depth / (rays @ -camera_pose(camera)[:3, 2])


@pytest.mark.gl
def test_the_world_pass_draws_the_terrain_through_the_numpy_air(renderer):
    """A terrain of one known colour (lit by an ambient alone) seen from 600 m: each terrain pixel is
    `AirBetween.seen_through` of that colour at the pixel's depth, as the numpy side computes it."""
    ambient = (0.6, 0.6, 0.6)
    lighting = Lighting(time_of_day=16.0, lights=(Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0), 0.0),), ambient=ambient)
    camera = Camera((0.0, 600.0, 2900.0), (0.0, 0.0, -3000.0), 60.0)
    terrain = Terrain(height=150.0)
    renderer.render(Scene(camera=camera, lighting=lighting, terrain=terrain), read_back=False)
    drawn = renderer.context.read_linear_rgb()
    depth = renderer.context.read_depth().astype(np.float64)
    on_terrain = depth < 1.0
    assert on_terrain.mean() > 0.3
    rays, distances = rays_and_distances(camera, depth)
    colour = np.asarray(terrain.color) * ambient
    air = air_between(scene_sky(lighting), camera.position)
    expected = air.seen_through(np.broadcast_to(colour, rays.shape), rays, distances)
    close = np.abs(drawn - expected) <= 0.01 * expected + 2e-3
    assert close.all(axis=-1)[on_terrain].mean() > 0.99
    # the air shows: the far terrain is measurably not its own colour
    far = on_terrain & (distances > 3000.0)
    assert np.abs(drawn[far] - colour).max(axis=-1).mean() > 0.02


@pytest.mark.gl
def test_a_far_cloud_gets_the_same_air_in_full_3d_and_as_an_impostor(renderer):
    """One cloud 15 km away under a narrow view: full 3D takes the air per particle, the impostor at its quad
    when drawn (never in its texture).  Measured: 57.7 dB, the cloud's mean colour within 0.04 of a level; the
    impostor drawn without the air: 43.0 dB, its mean 2.7 levels off."""
    valley = load_scene(VALLEY)
    cloud = valley.clouds[5]
    centre, _ = cloud.bounding_sphere()
    eye = centre + 15000.0 * np.array([0.6, 0.05, 0.8])
    camera = Camera(tuple(eye), tuple(centre), 4.0)
    scene = dataclasses.replace(valley, clouds=(cloud,), terrain=None, camera=camera)
    full, _ = renderer.render(scene, settings=FULL_3D)
    impostor_settings = dataclasses.replace(RenderSettings(mode="impostor"), ring_radius=np.inf)
    for _ in range(3):
        impostor, stats = renderer.render(scene, settings=impostor_settings)
    assert stats.plan.impostors_drawn == 1
    difference = compare(impostor, full)
    assert difference.psnr_db >= 50.0, difference
    sky = scene_sky(scene.lighting).radiance(pixel_rays(camera, RENDER_WIDTH, RENDER_HEIGHT), 1e-3)
    on_cloud = np.abs(full.astype(float) - np.round(255.0 * srgb_encode(sky))).max(axis=-1) > 8
    assert on_cloud.mean() > 0.05
    means = [image[on_cloud].astype(float).mean(axis=0) for image in (full, impostor)]
    assert np.abs(means[0] - means[1]).max() < 0.5, means


def test_a_dragged_slider_s_coarse_air_is_near_the_full_one():
    """The preview's 16 x 16 x 8 volume at 6 samples (3 ms to build against 133) against the full one, 1.5 km up at
    18:15: measured p99 0.0026 in the light added, 0.0097 in the transmittance."""
    rng = np.random.default_rng(5)
    sun = sun_direction(18.25)
    full = build_aerial_perspective(TABLES, 1500.0, sun)
    coarse = build_aerial_perspective(TABLES, 1500.0, sun, preview=True)
    assert coarse.in_scattered.shape == (8, 16, 16, 3)
    directions = rng.normal(size=(3000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    distances = MAX_DISTANCE_M * rng.random(3000) ** 2
    (full_radiance, full_transmittance), (radiance, transmittance) = (
        volume.radiance_and_transmittance(directions, distances) for volume in (full, coarse)
    )
    assert np.percentile(np.pi * PHYSICAL_EXPOSURE * np.abs(radiance - full_radiance), 99) < 0.01
    assert np.percentile(np.abs(transmittance - full_transmittance), 99) < 0.015


def _square(centre, side):
    """The corners (4, 3) of a square of `side` facing +z about `centre`: lower left, lower right, upper left,
    upper right."""
    steps = 0.5 * side * np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0]], dtype=np.float64)
    return np.asarray(centre, dtype=np.float64) + steps


def test_a_quad_is_cut_into_cells_by_the_angle_it_spans():
    """The air is read at the corners of a quad's cells: one cell for a far quad, cells of at most
    `AIR_CELL_ANGLE` for a near one, the most for a quad the eye is inside the sphere of."""
    eye = np.zeros(3)
    far, near, around = _square((0, 0, -20000.0), 500.0), _square((0, 0, -1000.0), 300.0), _square((0, 0, -1.0), 50.0)
    cells = air_cells(np.stack([far, near, around]), eye)
    assert cells[0] == 1 and cells[2] == AIR_MAX_CELLS
    half_diagonal = 150.0 * np.sqrt(2.0)
    span = 2.0 * np.arctan(half_diagonal / (1000.0 - half_diagonal))
    assert cells[1] == int(np.ceil(span / AIR_CELL_ANGLE)) and 1 < cells[1] < AIR_MAX_CELLS


def test_a_new_altitude_s_air_is_coarse_until_its_exact_volume_is_built():
    """The editor's air (`LiveAir`): a frame at a new altitude gets the coarse volume and the scene's sky at once
    while the exact ones are built in the background, then the exact ones, the very volume and sky a headless
    frame waits for; a frame at the next altitude meanwhile draws the nearest sky built."""
    sky = scene_sky(Lighting(time_of_day=11.75))
    eye = (0.0, 3456.0, 0.0)  # an altitude no other test draws from, so no volume of it is cached
    live = LiveAir()

    def built(count: int) -> None:
        for _ in range(400):
            if live.built >= count:
                break
            time.sleep(0.05)
        assert live.built == count

    try:
        first = live(sky, eye)
        assert first.volume.in_scattered.shape == (8, 16, 16, 3)
        assert live.sky_seen_from(sky, eye) is sky
        built(1)
        exact = live(sky, eye)
        assert exact.volume is air_between(sky, eye).volume and exact.volume.in_scattered.shape == (32, 32, 32, 3)
        assert live(sky, (0.0, 3460.0, 0.0)) is exact, "an eye within the same altitude step draws the same volume"
        seen = live.sky_seen_from(sky, eye).view
        assert seen.altitude_m == 3500.0 and np.array_equal(seen.table, sky.seen_from(eye).view.table)
        climbed = (0.0, 3620.0, 0.0)
        assert live.sky_seen_from(sky, climbed).view is seen  # until the 3,600 m sky is built
        live(sky, climbed)
        built(2)
        assert live.sky_seen_from(sky, climbed).view.altitude_m == 3600.0
    finally:
        live.close()


def test_a_sky_seen_from_an_eye_builds_the_eye_s_table_alone_and_the_editor_s_worker_builds_it(monkeypatch):
    """A scene's sky is made over its origin and drawn as an eye above it sees it (`SkyBackground.seen_from`): the
    eye's table is made, when first read, from the tables of the altitude knots around it (`altitude_knots`), and
    the origin's never; the editor's air (`LiveAir`) has its worker build the table, so the frame that reads it
    builds none."""
    built = []
    build = sky_view.build_sky_view_table
    monkeypatch.setattr(sky_view, "build_sky_view_table", lambda *args: built.append(args[3]) or build(*args))
    eye = (0.0, 2345.0, 0.0)
    for preview in (False, True):
        built.clear()
        seen = scene_sky(Lighting(time_of_day=10.35), preview).seen_from(eye)  # an hour no other test draws
        assert built == []
        assert seen.view.altitude_m == 2300.0
        assert np.isfinite(seen.view.table).all() and built == [2000.0, 2500.0]
    sky = scene_sky(Lighting(time_of_day=10.45))
    live = LiveAir()
    try:
        live(sky, eye)
        for _ in range(400):
            if live.built:
                break
            time.sleep(0.05)
        built.clear()
        assert live.sky_seen_from(sky, eye).view.table.shape == (108, 192, 3)
        assert built == []
    finally:
        live.close()


@pytest.mark.gl
def test_an_object_far_away_is_seen_through_the_air(renderer):
    """A 600 m box 6 km away, drawn with the air and without (`RenderSettings.aerial_perspective`): with it, each of
    its pixels is `AirBetween.seen_through` of the pixel without it, at the pixel's depth."""
    camera = Camera((0.0, 300.0, 6000.0), (0.0, 300.0, 0.0), 20.0)
    scene = Scene(
        camera=camera,
        lighting=Lighting(time_of_day=15.5),
        objects=(SceneObject("box", primitive="box", scale=600.0, position=(0.0, 300.0, 0.0)),),
    )
    drawn = {}
    for air in (True, False):
        settings = dataclasses.replace(FULL_3D, aerial_perspective=air)
        renderer.render(scene, settings=settings, read_back=False)
        drawn[air] = renderer.context.read_linear_rgb().astype(np.float64)
    depth = renderer.context.read_depth().astype(np.float64)
    on_box = depth < 1.0
    assert on_box.mean() > 0.05
    rays, distances = rays_and_distances(camera, depth)
    expected = air_between(scene_sky(scene.lighting), camera.position).seen_through(drawn[False], rays, distances)
    close = np.abs(drawn[True] - expected) <= 0.01 * expected + 2e-3
    assert close.all(axis=-1)[on_box].mean() > 0.99
    assert np.abs(drawn[True] - drawn[False]).max(axis=-1)[on_box].mean() > 0.01
