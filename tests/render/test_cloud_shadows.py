"""The clouds' shadows (`cloudcore.light.cloud_shadows`, `cloudcore.gl.shadow_map`): where a cloud's shadow falls,
how dark, clouds in one another's, the GL map against numpy's, and what is made again when."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.cloud_shadows import (
    MAP_RESOLUTION,
    PREVIEW_MAP_RESOLUTION,
    SLICES,
    beam_opacity,
    between_clouds_transmittance,
    light_space,
    opacity_map,
    sample_map,
)
from cloudcore.light.illumination import IlluminationCache, illuminate_clouds, shadowing_sun
from cloudcore.light.lighting import scene_lights
from cloudcore.maths.colour import srgb_decode
from cloudcore.model.cloud_records import Formation
from cloudcore.model.scene import Camera, Light, Lighting, Scene, Shading, Terrain
from cloudcore.model.settings import FULL_3D
from cloudcore.world.camera import projection_matrix, view_matrix
from cloudcore.world.sun import sun_direction
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH, ball

SUN = sun_direction(15.5)


def ground_point_along_sun(point, sun, ground_y=0.0) -> np.ndarray:
    """Where the sun's ray through `point` meets the level ground at `ground_y`."""
    point = np.asarray(point, dtype=np.float64)
    return point - (point[1] - ground_y) / sun[1] * np.asarray(sun)


def particles_of(clouds, shading=Shading()):
    centres = np.concatenate([c.centres for c in clouds])
    radii = np.concatenate([c.radii for c in clouds])
    opacity = beam_opacity(np.full(len(radii), shading.optical_depth), shading.albedo, shading.phase, shading.g)
    starts = np.concatenate([[0], np.cumsum([len(c.particles) for c in clouds])])
    return centres, radii, opacity, starts


@pytest.mark.parametrize("hours", [8.0, 12.0, 15.5, 18.25])
def test_a_cloud_and_its_ground_point_along_the_sun_share_a_texel(hours):
    """The map's view along the sun takes a cloud's centre and the ground point its sun's ray meets to one texel
    (the same (x, y)), the ground behind every slice and the centre within them."""
    sun = sun_direction(hours)
    cloud = ball((300.0, 1200.0, -400.0))
    centres, radii, _, _ = particles_of([cloud])
    space = light_space(centres, radii, sun, 256)
    centre = centres.mean(axis=0)
    ground = ground_point_along_sun(centre, sun)
    x, y, s = space.texel_coordinates(np.stack([centre, ground]))
    assert np.floor(x[0]) == np.floor(x[1]) and np.floor(y[0]) == np.floor(y[1])
    assert abs(x[0] - x[1]) < 1e-6 and abs(y[0] - y[1]) < 1e-6
    assert 0.0 < s[0] < SLICES < s[1]
    # the map's matrix says the same, in texture coordinates
    mapped = space.world_to_map() @ np.array([*ground, 1.0])
    assert np.allclose(mapped[:2] * space.size, [x[1], y[1]])


def test_the_ground_under_a_cloud_along_the_sun_is_in_its_shadow_and_elsewhere_not():
    cloud = ball((0.0, 1200.0, 0.0))
    centres, radii, opacity, _ = particles_of([cloud])
    space = light_space(centres, radii, SUN, 256)
    values = opacity_map(space, centres, radii, opacity)
    shadow = ground_point_along_sun(centres.mean(axis=0), SUN)
    under_the_cloud = np.array([0.0, 0.0, 0.0])  # straight below it: the sun comes in slanted, so it is lit
    beside = shadow + np.array([900.0, 0.0, 900.0])
    above = centres.mean(axis=0) + 600.0 * SUN  # between the cloud and the sun
    transmittance = np.exp(-sample_map(space, values, np.stack([shadow, under_the_cloud, beside, above])))
    assert transmittance[0] < 0.3
    assert transmittance[1:].tolist() == [1.0, 1.0, 1.0]


def test_a_particle_takes_out_of_the_beam_what_the_light_pass_does_not_send_on():
    """Behind a lone particle, at its axis, the map holds -ln(1 - b), b its beam opacity: alpha - sigma_eff."""
    radius = 100.0
    opacity = beam_opacity(np.array([8.0]), 0.9)
    assert 0.1 < opacity[0] < 0.2  # of alpha 0.9997 it sends on 0.86 (Rayleigh, albedo 0.9)
    space = light_space(np.zeros((1, 3)), [radius], SUN, 63)  # an odd count: a texel's centre on the axis
    values = opacity_map(space, np.zeros((1, 3)), [radius], opacity)
    behind = -200.0 * np.asarray(SUN)
    assert sample_map(space, values, behind[None])[0] == pytest.approx(-np.log1p(-opacity[0]), rel=1e-9)
    assert sample_map(space, values, (200.0 * np.asarray(SUN))[None])[0] == 0.0


def test_a_cloud_behind_another_toward_the_sun_receives_less_light():
    front = ball((0.0, 1200.0, 0.0), seed=1)
    behind = ball(np.array([0.0, 1200.0, 0.0]) - 1200.0 * np.asarray(SUN), seed=2)
    aside = ball((2500.0, 1200.0, 0.0), seed=3)
    centres, radii, opacity, starts = particles_of([front, behind, aside])
    through = np.split(between_clouds_transmittance(centres, radii, opacity, starts, SUN), starts[1:-1])
    assert through[0].tolist() == [1.0] * len(through[0])  # nothing between it and the sun
    assert through[2].tolist() == [1.0] * len(through[2])
    assert through[1].mean() < 0.6 and through[1].max() <= 1.0
    # alone, a cloud's own particles never shadow it here: Harris's light pass has them
    alone = between_clouds_transmittance(*particles_of([behind])[:3], [0, len(behind.particles)], SUN)
    assert alone.tolist() == [1.0] * len(alone)


def test_the_light_pass_dims_the_sun_alone_and_the_cache_keeps_it_while_the_clouds_and_sun_stay():
    front = ball((0.0, 1200.0, 0.0), seed=1)
    behind = ball(np.array([0.0, 1200.0, 0.0]) - 1200.0 * np.asarray(SUN), seed=2)
    clouds = [front, behind]
    lights = (Light(tuple(SUN), (1.0, 0.9, 0.8), 1.0), Light((0.0, 1.0, 0.0), (0.5, 0.6, 1.0), 0.3))
    shading = Shading()
    alone = illuminate_clouds(clouds, shading, lights, "raster")
    cache = IlluminationCache()
    shadowed = cache.incident(clouds, shading, lights, "raster", between_clouds=True)
    assert np.array_equal(shadowed[0], alone[0])
    assert shadowed[1][:, 0].mean() < 0.7 * alone[1][:, 0].mean()
    assert np.array_equal(shadowed[1][:, 1], alone[1][:, 1])  # the skylight is not the sun
    assert np.array_equal(cache.incident(clouds, shading, lights, "raster", between_clouds=True)[1], shadowed[1])
    assert cache.between_made == 1
    noon = (Light(tuple(sun_direction(12.0))), lights[1])
    # a dragged slider's look keeps the clouds' shadows of the sun before; the look after the drag makes its own
    cache.incident(clouds, shading, noon, "preview", between_clouds=True)
    assert cache.between_made == 1
    cache.incident(clouds, shading, noon, "raster", between_clouds=True)
    assert cache.between_made == 2
    # a sun that has set casts no shadow: the skylight, first of the lights that shine, is not dimmed
    night = (Light(tuple(SUN), intensity=0.0), lights[1])
    assert shadowing_sun(night) is None
    assert np.array_equal(cache.incident(clouds, shading, night, "raster", between_clouds=True)[1], alone[1][:, 1:])


def shadow_scene(cloud_shadows_on_terrain=True) -> tuple[Scene, np.ndarray, np.ndarray]:
    """A cloud over a level terrain seen from above at 15:30; (scene, the ground point of the cloud's centre along the
    sun, a ground point well outside its shadow)."""
    cloud = ball((0.0, 1200.0, 0.0), radius_m=300.0)
    shadow = ground_point_along_sun(cloud.centres.mean(axis=0), SUN)
    lit = shadow + np.array([0.0, 0.0, 1500.0])
    middle = 0.5 * (shadow + lit)
    camera = Camera(tuple(middle + [0.0, 3500.0, 1.0]), tuple(middle), 60.0)
    scene = Scene(
        camera=camera,
        lighting=Lighting(time_of_day=15.5),
        clouds=(cloud,),
        terrain=Terrain(size=(9000.0, 9000.0), resolution=65, height=1.0),
    )
    return scene, shadow, lit


def pixel_of(camera: Camera, point) -> tuple[int, int]:
    """(row, column), top row first, of world `point` in a RENDER_WIDTH x RENDER_HEIGHT frame."""
    clip = projection_matrix(camera.fov_y_deg, RENDER_WIDTH / RENDER_HEIGHT) @ view_matrix(camera) @ [*point, 1.0]
    ndc = clip[:2] / clip[3]
    column = int((ndc[0] + 1.0) / 2.0 * RENDER_WIDTH)
    row = int((1.0 - ndc[1]) / 2.0 * RENDER_HEIGHT)
    return row, column


@pytest.mark.gl
def test_the_rendered_ground_is_darker_where_the_cloud_shadows_it(renderer):
    scene, shadow, lit = shadow_scene()
    drawn = {}
    for shadows in (True, False):
        image, _ = renderer.render(scene, settings=dataclasses.replace(FULL_3D, cloud_shadows=shadows))
        drawn[shadows] = srgb_decode(image / 255.0).mean(axis=-1)
    shadowed, open_ground = pixel_of(scene.camera, shadow), pixel_of(scene.camera, lit)
    assert drawn[True][shadowed] < 0.5 * drawn[True][open_ground]
    assert drawn[True][open_ground] == pytest.approx(drawn[False][open_ground], rel=0.02)
    assert drawn[False][shadowed] == pytest.approx(drawn[False][open_ground], rel=0.05)


@pytest.mark.gl
@pytest.mark.parametrize("widest_m, as_points", [(40.0, True), (900.0, False)])
def test_the_gl_map_is_numpys(renderer, widest_m, as_points):
    """The map's particles drawn as point sprites, or as quads where one is wider than the GL's largest point (a
    particle of 900 m spans most of the 512 texels across this map), give numpy's map."""
    scene, _, _ = shadow_scene()
    particles = scene.clouds[0].particles.copy()
    particles[0, 3] = widest_m
    scene = dataclasses.replace(scene, clouds=(dataclasses.replace(scene.clouds[0], particles=particles),))
    renderer.render(scene, settings=FULL_3D, read_back=False)
    shadow_map = renderer.shadow_map
    assert shadow_map.drawn_as_points == as_points
    renderer.context.make_current()
    centres, radii, _, _ = particles_of(scene.clouds)
    # the GL map takes the particles' whole opacity (the ground's shadow, nearer the truth's than the beam's)
    opacity = -np.expm1(-np.full(len(radii), scene.shading.optical_depth))
    expected = opacity_map(shadow_map.space, centres, radii, opacity)
    assert expected.max() > 1.0
    assert np.abs(shadow_map.read() - expected).max() < 1e-4 * expected.max()


@pytest.mark.gl
def test_the_map_is_made_again_only_when_the_sun_or_the_clouds_change(renderer):
    scene, _, _ = shadow_scene()
    renderer.render(scene, settings=FULL_3D, read_back=False)
    made = renderer.shadow_map.made
    renderer.render(scene, settings=FULL_3D, read_back=False)
    renderer.render(scene, settings=FULL_3D, camera=dataclasses.replace(scene.camera, fov_y_deg=50.0), read_back=False)
    assert renderer.shadow_map.made == made
    renderer.render(scene, settings=FULL_3D, time_of_day=14.0, read_back=False)
    assert renderer.shadow_map.made == made + 1
    moved = dataclasses.replace(scene, clouds=(ball((100.0, 1200.0, 0.0), radius_m=300.0),))
    renderer.render(moved, settings=FULL_3D, time_of_day=14.0, read_back=False)
    assert renderer.shadow_map.made == made + 2


@pytest.mark.gl
def test_a_dragged_slider_s_look_draws_a_coarser_map_and_the_release_the_exact_picture(renderer):
    """A look of a dragged time-of-day slider (the preview light pass) has its map made at the preview's coarser
    texels, the ground under the cloud along the sun still in its shadow; the look after the release, at the hour
    before the drag, draws the very picture drawn before it, after a drag of several looks through that hour too."""
    scene, shadow, lit = shadow_scene()
    exact, _ = renderer.render(scene, settings=FULL_3D)
    exact_size = renderer.shadow_map.space.size
    dragged, _ = renderer.render(scene, settings=FULL_3D, time_of_day=15.45, illumination_method="preview")
    assert max(renderer.shadow_map.space.size) == PREVIEW_MAP_RESOLUTION < max(exact_size) == MAP_RESOLUTION
    ground = srgb_decode(dragged / 255.0).mean(axis=-1)
    assert ground[pixel_of(scene.camera, shadow)] < 0.5 * ground[pixel_of(scene.camera, lit)]
    released, _ = renderer.render(scene, settings=FULL_3D)
    assert renderer.shadow_map.space.size == exact_size
    assert np.array_equal(released, exact)
    for hours in (15.2, 15.5, 15.8):  # each look its preview light, map and sky; the scene's own hour among them
        look, _ = renderer.render(scene, settings=FULL_3D, time_of_day=hours, illumination_method="preview")
        assert not np.array_equal(look, exact)
    released, _ = renderer.render(scene, settings=FULL_3D)
    assert renderer.shadow_map.space.size == exact_size
    assert np.array_equal(released, exact)


def test_the_sun_of_explicit_lights_is_the_first():
    lighting = Lighting(time_of_day=None, lights=(Light((0.6, 0.8, 0.0)), Light((0.0, 1.0, 0.0))))
    assert shadowing_sun(scene_lights(lighting)[0]) == (0.6, 0.8, 0.0)


@pytest.mark.gl
def test_the_map_follows_a_forming_cloud_and_is_made_again_only_while_it_forms(renderer):
    """Before its formation starts a cloud casts no shadow, while it forms its shadow deepens (the map made again
    each frame), and once formed the map is held."""
    scene, _, _ = shadow_scene()
    forming = dataclasses.replace(scene.clouds[0], formation=Formation("form", 1.0, 2.0))
    scene = dataclasses.replace(scene, clouds=(forming,))
    depths, made = [], []
    for time_s in (0.5, 1.5, 2.5, 4.0, 5.0):
        renderer.render(scene, settings=FULL_3D, time_s=time_s, read_back=False)
        renderer.context.make_current()
        depths.append(renderer.shadow_map.read().max())
        made.append(renderer.shadow_map.made)
    assert depths[0] == 0.0
    assert 0.0 < depths[1] < depths[2] < depths[3] == depths[4]
    assert made[1] == made[0] + 1 and made[2] == made[1] + 1 and made[4] == made[3]
