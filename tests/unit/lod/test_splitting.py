"""Split layers around objects inside clouds (issue 5), on plans alone: no GL."""

import math

import numpy as np
import pytest

from cloudcore.lod.plan import LodState, plan_frame
from cloudcore.lod.splitting import layer_of
from cloudcore.lod.units import LodUnits
from cloudcore.model.scene import Camera
from cloudcore.model.settings import RenderSettings
from cloudcore.scenes.files import load_scene
from cloudcore.world.objects import ObjectPose, object_poses
from tests.conftest import VALLEY

VIEWPORT = (640, 480)
RNG = np.random.default_rng(5)
#: one cloud of 2,000 particles in a ball of 100 m about the origin
PARTICLES = RNG.normal(size=(2000, 3)) * 40.0
PARTICLES = PARTICLES[np.linalg.norm(PARTICLES, axis=1) < 90.0]
CENTRE, RADIUS = np.zeros((1, 3)), np.array([100.0])


def pose(position, radius=5.0) -> ObjectPose:
    model = np.eye(4)
    model[:3, 3] = position
    return ObjectPose(model, np.asarray(position, dtype=np.float64), radius)


def plan(camera, objects, settings=RenderSettings(mode="full"), records=None, particles=lambda _: PARTICLES):
    units = LodUnits.of_spheres(
        CENTRE, RADIUS, particle_counts=[len(PARTICLES)], radius_squares=[len(PARTICLES) * 25.0]
    )
    return plan_frame(units, camera, VIEWPORT, settings, LodState(records or {}), 1, objects, particles)


def layer_order_errors(frame_plan, object_centres, eye) -> list[str]:
    """Every way the plan's draw items break back-to-front order around the objects, in words."""
    errors = []
    items = frame_plan.draw_items
    for position, item in enumerate(items):
        if item.kind != "object":
            continue
        distance = float(np.linalg.norm(object_centres[item.index] - eye))
        for other_position, other in enumerate(items):
            if other.kind != "cloud" or item.index not in frame_plan.clouds[other.index].split_objects:
                continue
            if other_position < position and other.near < distance - 1e-9:
                errors.append(f"layer {other} drawn before object {item.index} reaches in front of it")
            if other_position > position and other.far > distance + 1e-9:
                errors.append(f"layer {other} drawn after object {item.index} reaches behind it")
    return errors


def particles_per_layer(particles, eye, splits) -> tuple:
    """The `particles` in each layer cut at `splits` (far to near) seen from `eye`, far to near."""
    distances = np.linalg.norm(particles - np.asarray(eye), axis=1)
    return tuple(np.bincount(layer_of(distances, splits), minlength=len(splits) + 1).tolist())


@pytest.mark.parametrize("azimuth_deg", range(0, 360, 45))
@pytest.mark.parametrize("mode", ["full", "impostor"])
def test_two_objects_in_one_cloud_give_three_layers_in_order_from_any_side(azimuth_deg, mode):
    a = math.radians(azimuth_deg)
    eye = np.array([600.0 * math.sin(a), 150.0, 600.0 * math.cos(a)])
    objects = (pose((-35.0, 0.0, 10.0)), pose((35.0, 0.0, -10.0)))
    frame = plan(Camera(tuple(eye), (0.0, 0.0, 0.0), 50.0), objects, RenderSettings(mode=mode))
    (cloud,) = frame.clouds
    assert cloud.kind == mode and cloud.layers == 3
    assert min(particles_per_layer(PARTICLES, eye, cloud.splits)) > 0, "every layer holds particles"
    kinds = [(item.kind, item.layer if item.kind == "cloud" else item.index) for item in frame.draw_items]
    far, near = sorted(range(2), key=lambda i: -np.linalg.norm(objects[i].centre - eye))
    assert kinds == [("cloud", 0), ("object", far), ("cloud", 1), ("object", near), ("cloud", 2)]
    assert layer_order_errors(frame, np.array([o.centre for o in objects]), eye) == []
    assert frame.stats().layers_drawn == 3 and frame.stats().objects_in_clouds == 2


def test_an_object_leaving_the_cloud_returns_it_to_one_impostor():
    camera = Camera((0.0, 100.0, 700.0), (0.0, 0.0, 0.0), 50.0)
    impostor = RenderSettings(mode="impostor")
    inside = plan(camera, (pose((0.0, 0.0, 20.0)),), impostor)
    assert inside.clouds[0].layers == 2 and inside.clouds[0].regenerate == "new"
    same = plan(camera, (pose((0.0, 0.0, 20.0)),), impostor, inside.records)
    assert same.clouds[0].regenerate is None, "nothing moved: the layer textures stay"
    left = plan(camera, (pose((0.0, 0.0, 400.0)),), impostor, same.records)
    assert left.clouds[0].layers == 1 and left.clouds[0].regenerate == "layers"
    assert [item.kind for item in left.draw_items] == ["cloud"] and left.objects_with_world == (0,)
    again = plan(camera, (pose((0.0, 0.0, 400.0)),), impostor, left.records)
    assert again.clouds[0].regenerate is None and again.stats().layers_rebuilt == 0


def test_layers_stay_until_the_object_passes_in_depth_a_particle_it_covers():
    camera = Camera((0.0, 0.0, 700.0), (0.0, 0.0, 0.0), 50.0)
    impostor = RenderSettings(mode="impostor")
    # behind the object on its line of sight, 10 m farther; and 50 m aside (4 degrees off, the object 0.4 wide)
    behind, aside = (0.0, 0.0, -10.0), (50.0, 0.0, -4.0)
    particles = np.array([behind, aside, (0.0, 40.0, 30.0)])
    first = plan(camera, (pose((0.0, 0.0, 0.0)),), impostor, particles=lambda _: particles)
    assert first.clouds[0].regenerate == "new" and first.clouds[0].layers == 2
    assert particles_per_layer(particles, camera.position, first.clouds[0].splits) == (2, 1)
    # 6 m back: past the particle aside (5.8 m farther than the object was), which it does not cover
    past_aside = plan(camera, (pose((0.0, 0.0, -6.0)),), impostor, first.records, particles=lambda _: particles)
    assert past_aside.clouds[0].regenerate is None
    past_behind = plan(camera, (pose((0.0, 0.0, -12.0)),), impostor, past_aside.records, particles=lambda _: particles)
    assert past_behind.clouds[0].regenerate == "layers" and past_behind.stats().layers_rebuilt == 2


def test_a_scene_without_objects_in_clouds_looks_at_no_particle():
    def refuse(_):
        raise AssertionError("particles looked at without an object inside the cloud")

    camera = Camera((0.0, 0.0, 700.0), (0.0, 0.0, 0.0), 50.0)
    outside = (pose((0.0, 0.0, 300.0)),)
    for mode in ("full", "impostor", "auto"):
        frame = plan(camera, outside, RenderSettings(mode=mode), particles=refuse)
        assert frame.objects_with_world == (0,) and frame.objects_between_layers == ()
        assert frame.stats().layers_drawn == 0
    no_split = plan(
        camera, (pose((0.0, 0.0, 0.0)),), RenderSettings(mode="full", split_objects=False), particles=refuse
    )
    assert no_split.objects_with_world == (0,) and no_split.clouds[0].layers == 1


def test_an_object_behind_the_camera_is_not_drawn_but_still_splits():
    camera = Camera((0.0, 0.0, 50.0), (0.0, 0.0, 200.0), 50.0)  # inside the cloud, looking away from it
    frame = plan(camera, (pose((0.0, 0.0, -60.0)),), RenderSettings(mode="auto"))
    assert frame.clouds[0].kind == "inside" and frame.clouds[0].layers == 2
    assert frame.objects_between_layers == () and frame.objects_with_world == ()


def test_objects_in_an_empty_or_zero_radius_cloud_are_finite():
    camera = Camera((0.0, 0.0, 700.0), (0.0, 0.0, 0.0), 50.0)
    frame = plan_frame(
        LodUnits.of_spheres(np.zeros((1, 3)), np.zeros(1)),
        camera,
        VIEWPORT,
        RenderSettings(),
        LodState(),
        1,
        (pose((0.0, 0.0, 0.0), radius=0.0),),
        lambda _: np.zeros((0, 3)),
    )
    assert frame.clouds[0].kind == "empty" and frame.objects_with_world == (0,)


def test_no_frame_of_the_default_flythrough_has_a_layer_order_error():
    """Every frame at 30 fps in auto mode, the impostor cache carried along as the renderer does."""
    scene = load_scene(VALLEY)
    spheres = [cloud.bounding_sphere() for cloud in scene.clouds]
    centres, radii = np.array([s[0] for s in spheres]), np.array([s[1] for s in spheres])
    path = scene.camera_path("flythrough")
    from cloudcore.maths.paths import camera_on_path

    units = LodUnits.of_spheres(
        centres,
        radii,
        particle_counts=[len(c.particles) for c in scene.clouds],
        radius_squares=[float(np.sum(c.radii**2)) for c in scene.clouds],
    )
    state, split_frames, errors = LodState(), 0, []
    settings = RenderSettings()
    for frame_index in range(int(path.duration * 30) + 1):
        t = frame_index / 30.0
        camera = camera_on_path(path, t, scene.camera.fov_y_deg)
        poses = object_poses(scene.objects, path.keys[0, 0] + t)
        frame = plan_frame(units, camera, VIEWPORT, settings, state, 1, poses, lambda i: scene.clouds[i].centres)
        state = frame.state
        split_frames += bool(frame.objects_between_layers)
        errors += [
            f"t={t:.2f}: {e}"
            for e in layer_order_errors(
                frame,
                np.array([p.centre for p in poses]),
                np.asarray(camera.position),
            )
        ]
    assert errors == []
    assert split_frames > 100, "the aircraft should cross a drawn cloud for seconds of the path"


def test_auto_mode_prices_an_impostor_with_an_object_moving_inside_as_remade_as_often_as_it_passes_particles():
    units = LodUnits.of_spheres(
        CENTRE, RADIUS, [10.0], particle_counts=[len(PARTICLES)], radius_squares=[len(PARTICLES) * 25.0]
    )
    camera = Camera((0.0, 0.0, 1500.0), (0.0, 0.0, 0.0), 60.0)
    settings = RenderSettings(ring_radius=math.inf)

    def prices(first, then):
        """The unit's impostor price a frame, its object moving from `first` to `then` (the eye still)."""
        state = plan_frame(units, camera, VIEWPORT, settings, LodState(), 1, [pose(first)], lambda _: PARTICLES).state
        planned = plan_frame(units, camera, VIEWPORT, settings, state, 1, [pose(then)], lambda _: PARTICLES)
        return planned.clouds[0].impostor_ms, planned.clouds[0].layers

    still_ms, layers = prices((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    # the 5 m object covers particles about every 10 m in depth: past one every 3 frames, or every 40
    fast_ms, _ = prices((0.0, 0.0, 0.0), (0.0, 0.0, 3.0))
    slow_ms, _ = prices((0.0, 0.0, 0.0), (0.0, 0.0, 0.25))
    aside_ms, _ = prices((0.0, 0.0, 0.0), (3.0, 0.0, 0.0))  # across the line of sight: 3 mm in depth
    unsplit_ms, _ = prices((0.0, 0.0, 900.0), (0.0, 0.0, 900.0))  # the object outside the cloud
    assert layers == 2
    # still (or moving across), its layers' impostor lasts as long as the eye lets it; moving in depth, until the
    # object passes a particle it covers
    assert still_ms < 0.2 * fast_ms and unsplit_ms < 0.2 * fast_ms and aside_ms < 0.2 * fast_ms
    assert 1.2 * still_ms < slow_ms < 0.25 * fast_ms
