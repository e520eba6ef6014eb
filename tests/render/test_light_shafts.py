"""Light shafts (`cloudcore.light.light_shafts`, `cloudcore.gl.light_shafts`): which part of a ray the clouds' shadow
map covers, the air's light taken in a shadow of known depth, the GL march against numpy's, and frames with and
without them."""

import dataclasses

import numpy as np
import pytest

from cloudcore.atmosphere.aerial_perspective import MAX_DISTANCE_M
from cloudcore.gl.light_shafts import shaft_reduction, shaft_size
from cloudcore.light.air_between import air_between
from cloudcore.light.cloud_shadows import SLICES, light_space, opacity_map
from cloudcore.light.light_shafts import shadowed_in_scattering, shadowed_share, shaft_segments
from cloudcore.light.sky_background import HORIZON_MARGIN, over_the_horizon, scene_sky
from cloudcore.maths.colour import srgb_decode
from cloudcore.model.scene import Camera, Lighting, Scene
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.resources import DEFAULT_SCENE
from cloudcore.scenes.files import load_scene
from cloudcore.world.camera import pixel_rays, projection_matrix, view_matrix
from cloudcore.world.sun import sun_direction
from cloudcore.world.terrain import height_at
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH
from tests.render.test_cloud_shadows import ball, particles_of

SUN = sun_direction(17.0)


def one_cloud_space(resolution=64):
    """The map's view over one round cloud 1.2 km up, under the 17:00 sun."""
    centres, radii, _, _ = particles_of([ball((0.0, 1200.0, 0.0), radius_m=400.0)])
    return light_space(centres, radii, SUN, resolution), centres, radii


def test_a_rays_segment_ends_on_the_prisms_faces_and_holds_only_its_points():
    space, _, _ = one_cloud_space()
    rng = np.random.default_rng(3)
    eye = np.array([3000.0, 200.0, 500.0])
    directions = rng.normal(size=(4000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    start, end = shaft_segments(space, eye, directions, np.full(len(directions), 20000.0))
    met = end > start
    assert 50 < met.sum() < len(directions)  # some rays cross the prism, most do not
    to_map = space.world_to_map()
    for t in (start[met], end[met]):
        points = eye + directions[met] * t[:, None]
        u, v, s = (points @ to_map[:3, :3].T + to_map[:3, 3]).T
        inside = (u > -1e-9) & (u < 1 + 1e-9) & (v > -1e-9) & (v < 1 + 1e-9) & (s > -1e-9)
        assert inside.all()
        on_face = np.minimum.reduce([np.abs(u), np.abs(u - 1), np.abs(v), np.abs(v - 1), np.abs(s)]) < 1e-9
        # a segment starts at the eye or on a face, ends on a face or at the ray's end (20 km)
        assert (on_face | (np.abs(t) < 1e-9) | (np.abs(t - 20000.0) < 1e-6)).all()
    # a point of a missed ray, sampled along it, is never inside
    missed = directions[~met][:200]
    along = np.linspace(0.0, 20000.0, 400)
    points = eye + missed[:, None, :] * along[None, :, None]
    u, v, s = np.moveaxis(points @ to_map[:3, :3].T + to_map[:3, 3], -1, 0)
    assert not ((u > 0.01) & (u < 0.99) & (v > 0.01) & (v < 0.99) & (s > 0.01)).any()


def test_a_ray_in_a_shadow_of_even_depth_loses_that_share_of_its_air_and_one_outside_none():
    """A map of optical depth tau everywhere in its footprint: a ray that runs inside the footprint behind every
    slice (under the clouds along the sun) loses 1 - e^-tau of the light its air adds there; one that misses the
    footprint loses nothing."""
    space, _, _ = one_cloud_space(resolution=256)
    width, height = space.size
    tau = 0.7
    values = np.full((SLICES, height, width), tau)
    air = air_between(scene_sky(Lighting(time_of_day=17.0)), (0.0, 0.0, 0.0))
    # the footprint's middle, on the ground: behind every slice; rays along the ground, short enough to stay in
    right, up = np.asarray(space.right), np.asarray(space.up)
    middle = (space.origin[0] + 0.5 * space.texel_m * width) * right + (
        space.origin[1] + 0.5 * space.texel_m * height
    ) * up
    forward = np.asarray(space.forward)
    eye = middle + forward * (-middle[1] / forward[1])  # slid along the sun down to the ground
    eye[1] = 10.0
    directions = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    distances = np.full(3, 100.0)
    taken = shadowed_in_scattering(air, space, values, eye, directions, distances)
    added = air.added(directions, distances)[0] - air.added(directions, np.zeros(3))[0]
    assert np.all(added > 0.0)
    np.testing.assert_allclose(taken, -np.expm1(-tau) * added, rtol=1e-6)
    far_away = eye + 50.0 * space.texel_m * width * right
    assert np.all(shadowed_in_scattering(air, space, values, far_away, directions, distances) == 0.0)


def test_the_light_taken_is_never_more_than_the_air_adds_and_grows_with_the_shadows_depth():
    space, centres, radii = one_cloud_space()
    air = air_between(scene_sky(Lighting(time_of_day=17.0)), (0.0, 0.0, 0.0))
    eye = np.array([2500.0, 100.0, 300.0])
    directions = pixel_rays(Camera(tuple(eye), (0.0, 600.0, 0.0), 60.0), 24, 18).reshape(-1, 3)
    distances = np.full(len(directions), MAX_DISTANCE_M)
    taken = [
        shadowed_in_scattering(
            air, space, opacity_map(space, centres, radii, np.full(len(radii), alpha)), eye, directions, distances
        )
        for alpha in (0.2, 0.9)
    ]
    whole = air.added(directions, distances)[0]
    assert taken[1].max() > 0.05 * whole.max()  # the cloud's shadow is on some of these rays
    assert np.all(taken[0] <= taken[1] + 1e-12)
    assert np.all((taken[1] >= 0.0) & (taken[1] <= whole + 1e-12))


def test_a_ray_that_ends_in_front_of_a_cloud_on_its_sun_side_takes_next_to_none_of_its_shadow():
    """The air between the eye and a cloud on the cloud's sun side is in no shadow of it: a ray toward the cloud
    that ends 50 m in front of its foremost particle keeps at least 98% of its air's light, though a cloud 6 km
    behind it spreads the map's slices 860 m deep (a point between two slices reads the depth linearly between them,
    so the air up to a slice in front of a cloud reads a little of it: docs/atmosphere.md, "The shafts and the air
    in front of the clouds"); the same rays carried on 3 km, through the cloud into its shadow, lose a sixth of the
    air's light past there (the median ray; each at least a fiftieth)."""
    sun = np.asarray(SUN)
    near = ball((0.0, 1200.0, 0.0), radius_m=400.0, particles=600)
    behind = ball(tuple(np.array([0.0, 1200.0, 0.0]) - 6000.0 * sun), radius_m=400.0, particles=600, seed=2)
    centres, radii, opacity, _ = particles_of([near, behind])
    space = light_space(centres, radii, SUN, 256)
    assert space.slice_m > 800.0
    values = opacity_map(space, centres, radii, opacity)
    eye = np.array([0.0, 1200.0, 0.0]) + 2500.0 * sun
    air = air_between(scene_sky(Lighting(time_of_day=17.0)), eye)
    # rays from the eye toward the near cloud's middle, within a third of its radius
    rng = np.random.default_rng(5)
    targets = np.array([0.0, 1200.0, 0.0]) + rng.normal(size=(40, 3)) * 40.0
    directions = targets - eye
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    foremost = float(np.max(near.centres @ sun + near.radii))  # along the sun, toward it
    # where each ray crosses the plane across the sun through the foremost particle, less 50 m
    ends = (eye @ sun - foremost) / -(directions @ sun) - 50.0
    added = air.added(directions, ends)[0] - air.added(directions, np.zeros(len(ends)))[0]
    taken = shadowed_in_scattering(air, space, values, eye, directions, ends, steps=48)
    assert np.all(added > 0.0)
    assert np.all(taken <= 0.02 * added + 1e-12), (taken / added).max()
    through = ends + 3000.0
    added_through = air.added(directions, through)[0] - air.added(directions, np.zeros(len(ends)))[0]
    taken_through = shadowed_in_scattering(air, space, values, eye, directions, through, steps=48)
    # of the air past the ray's first end, through the cloud and behind it
    behind = shadowed_share(taken_through - taken, added_through - added)
    assert np.all(behind > 0.02) and np.median(behind) > 0.15, (behind.min(), np.median(behind))


def shaft_scene() -> Scene:
    """A cloud between the eye and the 17:00 sun, the eye in its shadow's air, no terrain: every ray reaches the
    air volume's end."""
    cloud = ball((0.0, 1200.0, 0.0), radius_m=400.0, particles=600)
    flat = np.array([SUN[0], 0.0, SUN[2]]) / np.hypot(SUN[0], SUN[2])
    eye = -3000.0 * flat + np.array([0.0, 300.0, 0.0])
    return Scene(
        camera=Camera(tuple(eye), tuple(eye + 1000.0 * flat + [0.0, 250.0, 0.0]), 60.0),
        lighting=Lighting(time_of_day=17.0),
        clouds=(cloud,),
    )


def march_depth_distances(renderer, camera: Camera) -> np.ndarray:
    """(height, width) metres along each ray of the march to the depth it ended at (the terrain's, the clouds'
    nearest); inf where nothing was drawn."""
    depth = renderer.light_shafts.read_depth().astype(np.float64)
    height, width = depth.shape
    projection = projection_matrix(camera.fov_y_deg, RENDER_WIDTH / RENDER_HEIGHT)
    with np.errstate(divide="ignore"):
        view_depth = projection[2, 3] / (2.0 * depth - 1.0 + projection[2, 2])
    forward = -view_matrix(camera)[2, :3]
    along = view_depth / (pixel_rays(camera, width, height) @ forward)
    return np.where(depth < 1.0, along, np.inf)


@pytest.mark.gl
def test_the_gl_march_is_numpys(renderer):
    scene = shaft_scene()
    renderer.render(scene, settings=FULL_3D, read_back=False)
    renderer.context.make_current()
    march = renderer.light_shafts.read(blurred=False)
    width, height = shaft_size(RENDER_WIDTH, RENDER_HEIGHT, shaft_reduction(RENDER_WIDTH))
    assert march.shape == (height, width, 4)
    centres, radii, _, _ = particles_of(scene.clouds)
    opacity = -np.expm1(-np.full(len(radii), scene.shading.optical_depth))
    space = renderer.shadow_map.space
    values = opacity_map(space, centres, radii, opacity)
    air = air_between(scene_sky(scene.lighting), scene.camera.position)
    directions = pixel_rays(scene.camera, width, height).reshape(-1, 3)
    # no terrain: a ray is the sky's, marched to the volume's end, below the horizon at it (as the sky draws), but
    # where the cloud's nearest depth ends it (Yusov's cut)
    distances = np.minimum(march_depth_distances(renderer, scene.camera).ravel(), MAX_DISTANCE_M)
    sky = scene_sky(scene.lighting)
    low = (directions[:, 1] < sky.lowest_up()) & (distances >= MAX_DISTANCE_M)
    directions[low] = over_the_horizon(directions[low], sky.lowest_up() - HORIZON_MARGIN)
    # the march's dither: interleaved gradient noise at each pixel's centre, rows counted from the bottom
    column, row = np.meshgrid(np.arange(width) + 0.5, height - 0.5 - np.arange(height))
    offsets = np.modf(52.9829189 * np.modf(0.06711056 * column + 0.00583715 * row)[0])[0].ravel()
    taken = shadowed_in_scattering(air, space, values, scene.camera.position, directions, distances, offsets)
    share = shadowed_share(taken, air.added(directions, distances)[0]).reshape(height, width)
    assert share.max() > 0.2  # shafts in view
    assert np.abs(march[..., 3] - share).max() < 0.02
    taken = taken.reshape(height, width, 3)
    # the worst ray's error is a step's at a shadow's edge, where GL's filtering differs most from numpy's: each of
    # SHAFT_STEPS weighs 1/SHAFT_STEPS of it (2.3% of the largest at 6 steps, 1.5% at 12); the rest are within 1%
    error = np.abs(march[..., :3] - taken)
    assert error.max() < 0.03 * taken.max()
    assert np.percentile(error, 99) < 0.0125 * taken.max()
    # what the world reads: the march blurred by a 3x3 tent, its edges clamped
    padded = np.pad(march, ((1, 1), (1, 1), (0, 0)), mode="edge")
    tent = np.array([1.0, 2.0, 1.0])
    blurred = (
        sum(tent[dy] * tent[dx] * padded[dy : dy + height, dx : dx + width] for dy in range(3) for dx in range(3))
        / 16.0
    )
    assert np.abs(renderer.light_shafts.read() - blurred).max() < 2e-3 * max(blurred.max(), 1.0)


def frames_with_and_without_shafts(renderer, scene: Scene) -> dict[bool, np.ndarray]:
    frames = {}
    for shafts in (True, False):
        image, _ = renderer.render(scene, settings=dataclasses.replace(FULL_3D, light_shafts=shafts))
        frames[shafts] = srgb_decode(image / 255.0)
    return frames


@pytest.mark.gl
def test_shafts_only_darken_and_most_where_most_of_the_air_is_shadowed(renderer):
    frames = frames_with_and_without_shafts(renderer, shaft_scene())
    darker = (frames[False] - frames[True]).mean(axis=-1)
    assert darker.min() > -2.0 / 255.0  # never brighter (the 8-bit dither aside)
    assert darker.max() > 0.02
    renderer.context.make_current()
    block = shaft_reduction(RENDER_WIDTH)
    shares = np.kron(renderer.light_shafts.read()[..., 3], np.ones((block, block)))
    shares = shares[:RENDER_HEIGHT, :RENDER_WIDTH]
    most, least = shares > np.percentile(shares, 80), shares < np.percentile(shares, 20)
    assert darker[most].mean() > 2.0 * darker[least].mean()


@pytest.mark.gl
def test_a_view_whose_air_no_shadow_reaches_is_drawn_as_without_shafts(renderer):
    scene = shaft_scene()
    # on the sun's side of the cloud, looking toward the sun: neither the eye nor its rays are in the shadow's air
    flat = np.array([SUN[0], 0.0, SUN[2]]) / np.hypot(SUN[0], SUN[2])
    eye = 3000.0 * flat + np.array([0.0, 300.0, 0.0])
    camera = Camera(tuple(eye), tuple(eye + 1000.0 * flat + [0.0, 250.0, 0.0]), 60.0)
    frames = frames_with_and_without_shafts(renderer, dataclasses.replace(scene, camera=camera))
    renderer.context.make_current()
    assert renderer.light_shafts.read().max() == 0.0
    assert np.abs(frames[True] - frames[False]).max() == 0.0


@pytest.mark.gl
def test_a_dragged_slider_s_look_is_drawn_without_shafts_and_the_release_with_them(renderer):
    """A dragged time-of-day slider's look (the preview light pass) marches no shafts: the picture it draws with
    them asked for is the one drawn without them; the look after the release marches them again, the picture
    with them."""
    scene = shaft_scene()
    frames = {}
    for shafts in (True, False):
        settings = dataclasses.replace(FULL_3D, light_shafts=shafts)
        frames[shafts], _ = renderer.render(scene, settings=settings, time_of_day=16.9, illumination_method="preview")
        assert renderer.light_shafts is None  # the dragged light's world pass never marched
    assert np.array_equal(frames[True], frames[False])
    released, _ = renderer.render(scene, settings=FULL_3D)
    assert renderer.light_shafts is not None
    without, _ = renderer.render(scene, settings=dataclasses.replace(FULL_3D, light_shafts=False))
    assert not np.array_equal(released, without)


#: a point of the march's depth this high over the ground is a cloud's (the default scene's hang 1 km and more up)
CLOUDS_OVER_GROUND_M = 300.0


def turned(camera: Camera, degrees: float) -> Camera:
    """`camera` turned `degrees` about the up through its eye."""
    eye, target = np.asarray(camera.position, dtype=np.float64), np.asarray(camera.look_at, dtype=np.float64)
    angle = np.radians(degrees)
    x, z = (target - eye)[[0, 2]]
    ahead = np.array([x * np.cos(angle) - z * np.sin(angle), (target - eye)[1], x * np.sin(angle) + z * np.cos(angle)])
    return dataclasses.replace(camera, look_at=tuple(eye + ahead))


@pytest.mark.gl
def test_the_marchs_terrain_depth_is_the_ground_of_each_view_in_turn(renderer):
    """The march's terrain depth (the coarse surfaces of the tiles in view, drawn in one call from triangles
    gathered when the tiles in view change) lies on the ground, and covers every ray that meets it, in a view
    after others looking elsewhere: triangles left over from the view before would leave holes or stray ground."""
    scene = load_scene(DEFAULT_SCENE)
    width, height = shaft_size(RENDER_WIDTH, RENDER_HEIGHT, shaft_reduction(RENDER_WIDTH))
    cloud_rays = []
    for degrees in (0.0, 120.0, 240.0, 0.0):
        camera = turned(scene.camera, degrees)
        renderer.render(scene, camera=camera, read_back=False)
        renderer.context.make_current()
        depth = renderer.light_shafts.read_depth()
        assert depth.shape == (height, width)
        projection = projection_matrix(camera.fov_y_deg, RENDER_WIDTH / RENDER_HEIGHT)
        view_depth = projection[2, 3] / (2.0 * depth.astype(np.float64) - 1.0 + projection[2, 2])
        rays = pixel_rays(camera, width, height)
        forward = -view_matrix(camera)[2, :3]
        eye = np.asarray(camera.position, dtype=np.float64)
        drawn = depth < 1.0
        points = eye + rays[drawn] * (view_depth[drawn] / (rays[drawn] @ forward))[:, None]
        over_ground = points[:, 1] - height_at(scene.terrain, points[:, 0], points[:, 2])
        # the clouds' nearest depth (Yusov's cut) hangs over the ground: never under it
        clouds = over_ground > CLOUDS_OVER_GROUND_M
        cloud_rays.append(np.count_nonzero(clouds))
        # on the coarse surface (every 4th vertex of tiles that grow with the distance): off the ground by a small
        # share of the distance
        off_by = np.abs(over_ground[~clouds]) / np.linalg.norm(points[~clouds] - eye, axis=1)
        assert np.percentile(off_by, 95) < 0.015
        assert off_by.max() < 0.05
        # every ray that meets the ground within 8 km, 20 m past it (a silhouette's rays aside), is drawn
        reach = np.arange(20.0, 8000.0, 20.0)
        along = eye + rays[..., None, :] * reach[:, None]
        below = along[..., 1] < height_at(scene.terrain, along[..., 0], along[..., 2]) - 20.0
        meets = below.any(axis=-1)
        assert meets.sum() > 0.2 * meets.size  # ground in view
        assert np.count_nonzero(meets & ~drawn) <= 0.01 * meets.sum()
    assert max(cloud_rays) > 0  # the clouds' nearest depth in some view


def upsampled(values: np.ndarray) -> np.ndarray:
    """The march's (height, width, ...) values at the frame's pixels, a march pixel's over its block."""
    block = shaft_reduction(RENDER_WIDTH)
    return np.repeat(np.repeat(values, block, axis=0), block, axis=1)[:RENDER_HEIGHT, :RENDER_WIDTH]


@pytest.mark.gl
def test_the_marchs_rays_end_at_the_clouds_nearest_particle():
    """Yusov's cut: a march ray through the cloud ends at the nearest of the particles whose discs' cores
    (`NEAREST_DEPTH_CORE` of their radii) it crosses, at their centres' depth; one that passes clear of every core
    reaches the air's end.  From 1.3 km, where the cloud's disc needs every particle's core
    (`nearest_depth_particles`; a far cloud draws every k-th)."""
    from cloudcore.gl.frame import FrameRenderer
    from cloudcore.gl.splats import NEAREST_DEPTH_CORE

    scene = shaft_scene()
    flat = np.array([SUN[0], 0.0, SUN[2]]) / np.hypot(SUN[0], SUN[2])
    eye = np.array([0.0, 1000.0, 0.0]) - 1300.0 * flat
    scene = dataclasses.replace(scene, camera=Camera(tuple(eye), (0.0, 1200.0, 0.0), 60.0))
    with FrameRenderer(RENDER_WIDTH, RENDER_HEIGHT) as renderer:
        renderer.render(scene, settings=FULL_3D, read_back=False)
        renderer.context.make_current()
        distances = march_depth_distances(renderer, scene.camera)
        height, width = distances.shape
        centres, radii, _, _ = particles_of(scene.clouds)
        rays = pixel_rays(scene.camera, width, height).reshape(-1, 3)
        eye = np.asarray(scene.camera.position, dtype=np.float64)
        forward = -view_matrix(scene.camera)[2, :3]
        to_centres = centres - eye
        along = rays @ to_centres.T  # (rays, particles): the centres' distance along each ray
        across = np.sqrt(np.maximum(np.sum(to_centres**2, axis=1) - along**2, 0.0))
        # a disc at the centre's depth, seen from the ray: its distance along the ray where the ray meets that depth
        at_depth = (to_centres @ forward)[None, :] / (rays @ forward)[:, None]
        core = NEAREST_DEPTH_CORE * radii
        # a point is at least a pixel wide: a core smaller than a march pixel may cover a pixel whose centre it misses
        pixel_m = along * 2.0 * np.tan(np.radians(0.5 * scene.camera.fov_y_deg)) / height
        crossed = across < 0.7 * core  # well inside a core, whatever a march pixel's rasterisation
        clear = ~np.any(across < 1.3 * core + pixel_m, axis=1)
        drawn = distances.ravel()
        hit = np.any(crossed, axis=1)
        assert hit.sum() > 10 and clear.sum() > 0.5 * len(rays)
        nearest = np.where(crossed, at_depth, np.inf).min(axis=1)
        # never behind the nearest core the ray crosses well inside (the window depth's resolution there aside, a
        # metre at 3 km)
        assert np.all(drawn[hit] <= nearest[hit] * (1.0 + 1e-3))
        # and every ray cut is cut at the depth of a particle whose core it crosses, or passes within a march pixel of
        cut = np.isfinite(drawn)
        near = (across < 1.3 * core + pixel_m) & (np.abs(at_depth - np.where(cut, drawn, 0.0)[:, None]) < 3.0)
        assert np.all(near[cut].any(axis=1))
        assert np.all(np.isinf(drawn[clear]))


def darkened_by_the_shafts(renderer, scene: Scene, settings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(how much darker each pixel is with the shafts than without (linear), the march's cloud pixels (its rays
    cut at a cloud), the light the march took), each at the frame's pixels, drawn by `settings`."""
    frames = {}
    for shafts in (False, True):
        renderer.render(scene, settings=dataclasses.replace(settings, light_shafts=shafts))  # impostors made
        image, _ = renderer.render(scene, settings=dataclasses.replace(settings, light_shafts=shafts))
        frames[shafts] = srgb_decode(image / 255.0)
    renderer.context.make_current()
    cloud = upsampled(np.isfinite(march_depth_distances(renderer, scene.camera)))
    return frames[False] - frames[True], cloud, upsampled(renderer.light_shafts.read()[..., :3])


@pytest.mark.gl
@pytest.mark.parametrize(
    "settings",
    [FULL_3D, RenderSettings(mode="impostor"), dataclasses.replace(FULL_3D, cloud_resolution_scale=0.5)],
    ids=["full_3d", "impostor", "full_3d_at_half_resolution"],
)
def test_a_cloud_toward_the_sun_loses_the_light_its_shadow_takes_from_the_air_in_front_of_it(renderer, settings):
    """The air between the eye and a cloud that hangs between it and the sun lies in the cloud's shadow: the
    shafts take its light off the cloud's pixels as they take it off the sky's (the march cut at the cloud's
    nearest depth, each cloud's own air scaled by the share left), whichever representation draws the cloud.
    Without the cut the cloud kept its air's light but at its thin fringe: its pixels darkened by 27% of the light
    taken in front of them."""
    darker, cloud, taken = darkened_by_the_shafts(renderer, shaft_scene(), settings)
    assert renderer.last_plan.stats().clouds_by_kind[settings.mode] == 1
    assert cloud.mean() > 0.02
    assert darker[cloud].mean() > 0.75 * taken[cloud].mean()
    assert darker[cloud].mean() < 1.1 * taken[cloud].mean()
    assert darker.min() > -2.0 / 255.0  # never brighter (the 8-bit dither aside)


@pytest.mark.gl
def test_a_cloud_is_darkened_by_the_shafts_alike_in_full_3d_and_as_its_impostor(renderer):
    """One cloud is never drawn two ways: its impostor's quad reads the shafts' share as its particles do, and the
    sky around it is the same march's."""
    full, cloud, _ = darkened_by_the_shafts(renderer, shaft_scene(), FULL_3D)
    impostor, _, _ = darkened_by_the_shafts(renderer, shaft_scene(), RenderSettings(mode="impostor"))
    assert abs(impostor[cloud].mean() - full[cloud].mean()) < 0.15 * full[cloud].mean()
    # the sky's pixels darken alike (the impostor's edge is not its particles' exactly)
    assert np.percentile(np.abs(impostor - full)[~cloud], 99) < 2.0 / 255.0
