"""The planet's ground past a terrain's square (`cloudcore.light.far_ground`, `SkyBackground.radiance(...,
far_ground=)`): the sky-view table's air in front of the ground and its transmittance to it, the ground's colour
the terrain's at its edge, and the terrain's edge through the air's volume meeting it."""

import dataclasses

import numpy as np

from cloudcore.atmosphere.geometry import distance_to_ground
from cloudcore.atmosphere.parameters import EARTH
from cloudcore.atmosphere.sky_view import eye_radius
from cloudcore.atmosphere.transmittance import optical_depth
from cloudcore.gl.world import terrain_vertex_light
from cloudcore.light.air_between import air_between
from cloudcore.light.far_ground import edge_colour, far_ground_box, far_ground_colour
from cloudcore.light.lighting import scene_lights
from cloudcore.light.sky_background import scene_sky
from cloudcore.light.terrain_light import terrain_light
from cloudcore.model.scene import Camera, Lighting, Terrain
from cloudcore.world.camera import pixel_rays, projection_matrix, view_matrix
from cloudcore.world.terrain import height_at
from cloudcore.world.terrain_tiles import SKIRT_CELLS, TILE_CELLS, leaf_tiles, tile_frame, tile_meshes

LIGHTING = Lighting(time_of_day=15.5)
#: the cumulus field demo's terrain: 120 km square, no reach
FIELD = Terrain(size=(120000.0, 120000.0), resolution=128, height=400.0, seed=7)


def light():
    lights, ambient = scene_lights(LIGHTING)
    return terrain_light(LIGHTING, lights, ambient)


def test_the_table_s_transmittance_to_the_ground_is_the_exponential_of_the_optical_depth():
    view = scene_sky(LIGHTING).seen_from((0.0, 2000.0, 0.0)).view
    r = eye_radius(EARTH, view.altitude_m)
    for down_deg in (2.0, 5.0, 20.0, 60.0):
        direction = np.array([np.cos(np.radians(down_deg)), -np.sin(np.radians(down_deg)), 0.0])
        length = distance_to_ground(r, direction[1], EARTH.bottom_radius_m)
        depth = optical_depth(EARTH, r, direction[1], length, 4000)
        np.testing.assert_allclose(view.ground_transmittance(direction), np.exp(-depth), rtol=0.02, err_msg=down_deg)


def test_the_ground_past_the_edge_is_the_terrain_s_edge_through_the_air():
    """The sky's far ground and the terrain's edge through the air's volume (as the world pass draws its vertices)
    at points of the edge within the volume's reach, from 10 km over the field and from outside it: within 5%
    (measured 0.1-3.4%: the volume's texels against the table's rows), where the air at the horizon drawn before
    was 40% off the terrain's colour."""
    ground = far_ground_colour(FIELD, light())
    half = tile_frame(FIELD).half_side_m
    for eye in (np.array([-20000.0, 10000.0, 3000.0]), np.array([-80000.0, 2000.0, 3000.0])):
        sky = scene_sky(LIGHTING).seen_from(eye)
        air = air_between(scene_sky(LIGHTING), eye)
        edge = np.array([[x, 0.0, z] for x in (-half, half) for z in np.linspace(-half, half, 9)])
        offsets = edge - eye
        distances = np.linalg.norm(offsets, axis=1)
        near = distances < 62000.0
        directions = offsets[near] / distances[near, None]
        terrain = air.seen_through(ground, directions, distances[near])
        far = sky.radiance(directions, 1e-3, far_ground=ground)
        np.testing.assert_allclose(far, terrain, rtol=0.05)
        horizon = sky.radiance(directions, 1e-3)
        assert np.max(np.abs(horizon / terrain - 1.0)) > 0.15


def test_the_far_ground_fades_into_the_haze_toward_the_horizon():
    """Looking further down the ground is nearer and more of its colour comes through; at the horizon only the
    air is left: from 10 km, the transmittance to the ground grows from the horizon to the nadir."""
    sky = scene_sky(LIGHTING).seen_from((0.0, 10000.0, 0.0))
    down = np.radians(np.linspace(3.3, 90.0, 40))
    directions = np.stack([np.cos(down), -np.sin(down), np.zeros_like(down)], axis=1)
    through = sky.view.ground_transmittance(directions)
    assert np.all(np.diff(through, axis=0) >= -1e-9)
    assert through[0, 2] < 0.2 and through[-1, 2] > 0.5
    assert np.all(np.isfinite(sky.radiance(directions, 1e-3, far_ground=far_ground_colour(FIELD, light()))))


def test_the_far_ground_s_colour_is_the_terrain_s_at_its_edge_lit_as_a_level_vertex():
    """A terrain coloured by height, its mountains rising past the valley's sides to its edge: the far ground takes
    the colour of the edge's heights (snow), not the valley's, lit as the terrain lights a level vertex."""
    ramp = ((0.0, 0.3, 0.4, 0.2), (1500.0, 0.9, 0.9, 0.9))
    snowy = dataclasses.replace(FIELD, size=(6000.0, 6000.0), reach=30000.0, relief=3000.0, color_ramp=ramp)
    edge = edge_colour(snowy)
    half = tile_frame(snowy).half_side_m
    heights = height_at(snowy, np.linspace(-half, half, 64), np.full(64, half))
    assert heights.mean() > 1500.0 and edge[2] > 0.8
    lit = light()
    sun, rest = terrain_vertex_light(np.array([[0.0, 1.0, 0.0]]), edge, lit)
    np.testing.assert_allclose(far_ground_colour(snowy, lit), (sun + rest)[0])


def test_no_skirt_hangs_below_the_origin_s_level_and_the_square_s_edge_is_a_wall_down_to_it():
    """Seen from outside the square, under its edge, a skirt hung below the origin's level stood in front of the
    ground drawn past it (the field's hills are all above it); the skirts still hang past a coarser neighbour's
    edge (tests/unit/world/test_terrain_tiles.py)."""
    frame = tile_frame(FIELD)
    positions, _ = tile_meshes(FIELD, frame, leaf_tiles(frame, (-80000.0, 2000.0, 3000.0)))
    grid = (TILE_CELLS + 1) ** 2
    surface, skirts = positions[:, :grid], positions[:, grid:]
    assert surface[..., 1].min() >= 0.0
    assert skirts[..., 1].min() == 0.0
    on_edge = np.maximum(np.abs(skirts[..., 0]), np.abs(skirts[..., 2])) >= frame.half_side_m
    assert on_edge.any() and np.all(skirts[on_edge][:, 1] == 0.0)
    # inside the square, where the skirts close the gaps between levels, they still hang
    assert np.any(skirts[~on_edge][:, 1] < surface[..., 1].min() + SKIRT_CELLS * frame.cell_m)


def _every_pixel_past_the_edge(camera: Camera, size, planet_ground, half_side_m) -> np.ndarray:
    """(height, width) bool, bottom row first: each pixel centre's ray meets the ground at least as far as the
    square's nearest edge, below the horizon (the pixels whose ground may show past the terrain)."""
    width, height = size
    rays = pixel_rays(camera, width, height)[::-1]  # bottom row first, as the window's boxes count
    altitude, radius = planet_ground
    ground = distance_to_ground(radius + altitude, rays[..., 1], radius)
    eye = np.asarray(camera.position)
    edge = max(min(half_side_m - abs(eye[0]), half_side_m - abs(eye[2])), 0.0)
    return np.isfinite(ground) & (ground >= edge)


def _box_of(camera: Camera, size, planet_ground, half_side_m):
    projection = projection_matrix(camera.fov_y_deg, size[0] / size[1])
    inverse = np.linalg.inv(projection @ view_matrix(camera))
    return far_ground_box(inverse, camera.position, size, planet_ground, half_side_m)


def test_the_far_ground_s_box_holds_every_pixel_whose_ground_lies_past_the_square():
    """The box the world pass writes the far ground's depth in (a pass writing its pixels' depth costs llvmpipe
    every pixel it covers) holds every pixel whose ray meets the ground past the square's nearest edge, tested at
    every pixel: from the default view (a band a few pixels deep along the horizon, not the screen below it), from
    10 km up, rolled toward the horizon's ends, and from outside the square (every pixel below the horizon)."""
    size, half = (640, 480), 40000.0
    planet = (EARTH.bottom_radius_m,)
    views = {
        "default": (Camera((450.0, 330.0, 2900.0), (-250.0, 850.0, -600.0)), 350.0),
        "from 10 km": (Camera((-20000.0, 10000.0, 3000.0), (0.0, 9000.0, 30000.0), 70.0), 10020.0),
        "down a slope": (Camera((30000.0, 600.0, -1000.0), (39000.0, 200.0, -9000.0)), 620.0),
        "outside": (Camera((-80000.0, 2000.0, 3000.0), (0.0, 1000.0, 3000.0)), 2020.0),
    }
    heights = {}
    for name, (camera, altitude) in views.items():
        ground = (altitude, planet[0] - 20.0)
        needed = _every_pixel_past_the_edge(camera, size, ground, half)
        assert needed.any(), name  # each view sees some ground past the square
        box = _box_of(camera, size, ground, half)
        assert box is not None, name
        x, y, width, height = box
        inside = np.zeros(needed.shape, dtype=bool)
        inside[y : y + height, x : x + width] = True
        assert not (needed & ~inside).any(), name
        heights[name] = height
    assert heights["default"] < 0.15 * size[1]  # the band along the horizon, not the terrain below it
    below_horizon = _every_pixel_past_the_edge(views["outside"][0], size, (2020.0, planet[0] - 20.0), half)
    assert heights["outside"] >= np.flatnonzero(below_horizon.any(axis=1)).size


def test_no_far_ground_box_where_the_view_sees_no_ground_past_the_square():
    """Looking up from the valley, or down into it from within the square, no pixel's ground lies past the edge."""
    size, half = (320, 240), 40000.0
    ground = (350.0, EARTH.bottom_radius_m - 20.0)
    up = Camera((0.0, 330.0, 0.0), (0.0, 2000.0, -1000.0))
    down = Camera((0.0, 330.0, 0.0), (0.0, -2000.0, -1000.0))
    for camera in (up, down):
        assert not _every_pixel_past_the_edge(camera, size, ground, half).any()
        assert _box_of(camera, size, ground, half) is None
