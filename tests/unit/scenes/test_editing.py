"""Editing as pure functions: picking, adding particles and clouds, undo and redo."""

import numpy as np
import pytest

from cloudcore.model.scene import Camera, Cloud, Scene
from cloudcore.scenes.editing import History, add_cloud, add_particle, delete_cloud, pick_ray, point_at_altitude


def test_the_centre_of_the_viewport_picks_along_the_view_direction():
    camera = Camera((0.0, 100.0, 0.0), (0.0, 100.0, -10.0), 60.0)
    origin, direction = pick_ray(camera, 4 / 3, 0.5, 0.5)
    np.testing.assert_allclose(origin, [0.0, 100.0, 0.0])
    np.testing.assert_allclose(direction, [0.0, 0.0, -1.0], atol=1e-12)
    _, top = pick_ray(camera, 4 / 3, 0.5, 0.0)  # the top edge is half the field of view up
    assert np.degrees(np.arcsin(top[1])) == pytest.approx(30.0)


def test_a_click_lands_on_the_altitude_plane_or_nowhere():
    origin, direction = np.array([0.0, 100.0, 0.0]), np.array([0.0, 0.6, -0.8])
    np.testing.assert_allclose(point_at_altitude(origin, direction, 700.0), [0.0, 700.0, -800.0])
    assert point_at_altitude(origin, direction, 50.0) is None  # behind the eye
    assert point_at_altitude(origin, np.array([0.0, 0.0, -1.0]), 700.0) is None  # parallel


def test_edits_make_new_scenes_and_history_undoes_them():
    scene = Scene(clouds=(Cloud("a"),))
    history = History(scene)
    history.apply(add_particle(history.current, 0, (1.0, 2.0, 3.0), 10.0))
    history.apply(add_cloud(history.current))
    assert [c.name for c in history.current.clouds] == ["a", "cloud0"]
    assert len(scene.clouds[0].particles) == 0  # the original is untouched
    assert history.undo() and history.undo() and not history.undo()
    assert history.current is scene
    assert history.redo() and len(history.current.clouds[0].particles) == 1
    history.apply(delete_cloud(history.current, 0))
    assert not history.redo()  # a new edit forgets the redone future
    with pytest.raises(ValueError, match="radius > 0"):
        add_particle(scene, 0, (0.0, 0.0, 0.0), 0.0)


def test_navigation_keeps_distances_and_orbits_by_the_asked_angle():
    from cloudcore.lod.impostors import translation_error_deg
    from cloudcore.world.navigation import moved, orbited, turned

    camera = Camera((0.0, 100.0, 500.0), (0.0, 100.0, 0.0), 60.0)
    around = orbited(camera, 1.0)
    assert translation_error_deg(camera.look_at, camera.position, around.position) == pytest.approx(1.0)
    assert np.linalg.norm(np.subtract(around.position, around.look_at)) == pytest.approx(500.0)
    ahead = moved(camera, forward=100.0)
    np.testing.assert_allclose(ahead.position, [0.0, 100.0, 400.0], atol=1e-9)
    np.testing.assert_allclose(
        np.subtract(ahead.look_at, ahead.position), [0.0, 0.0, -500.0], atol=1e-9
    )  # look-at moves along
    up = turned(camera, 0.0, 200.0)  # clamped short of straight up
    assert 0.0 < np.subtract(up.look_at, up.position)[1] < 500.0


def test_a_ray_enters_the_nearest_sphere_ahead_and_leaves_one_it_starts_in():
    from cloudcore.scenes.editing import first_hit

    origin, direction = np.zeros(3), np.array([0.0, 0.0, -1.0])
    centres = [[0.0, 0.0, -100.0], [0.0, 0.0, -50.0], [0.0, 5.0, 20.0], [30.0, 0.0, -10.0]]
    radii = [10.0, 10.0, 10.0, 10.0]  # behind the eye, and off to the side: never hit
    index, distance = first_hit(origin, direction, centres, radii)
    assert (index, distance) == (1, pytest.approx(40.0))
    grazing = first_hit(origin, direction, [[3.0, 4.0, -50.0]], [5.0])  # passes 5 m from the centre
    assert grazing == (0, pytest.approx(50.0))
    assert first_hit(origin, direction, [[3.0, 4.1, -50.0]], [5.0]) is None
    assert first_hit(origin, direction, [[0.0, 0.0, -2.0]], [10.0]) == (0, pytest.approx(12.0))  # inside
    assert first_hit(origin, direction, np.zeros((0, 3)), np.zeros(0)) is None


def test_a_click_lands_on_the_selected_cloud_surface_and_picks_across_clouds():
    from cloudcore.scenes.editing import pick_particle, point_on_cloud

    near = Cloud("near", [[0.0, 0.0, -100.0, 20.0], [0.0, 0.0, -60.0, 5.0]])
    far = Cloud("far", [[0.0, 0.0, -30.0, 10.0], [50.0, 0.0, 0.0, 1.0]])
    origin, direction = np.zeros(3), np.array([0.0, 0.0, -1.0])
    np.testing.assert_allclose(point_on_cloud(near, origin, direction), [0.0, 0.0, -55.0])
    assert point_on_cloud(near, origin, np.array([1.0, 0.0, 0.0])) is None
    cloud, particle, point = pick_particle(Scene(clouds=(near, far)), origin, direction)
    assert (cloud, particle) == (1, 0)  # the nearest particle of any cloud wins
    np.testing.assert_allclose(point, [0.0, 0.0, -20.0])
    assert pick_particle(Scene(clouds=(Cloud("empty"),)), origin, direction) is None


def test_particles_are_added_erased_moved_and_resized():
    from cloudcore.scenes.editing import add_particles, delete_particles, particles_within, translated, with_mean_radius

    scene = Scene(clouds=(Cloud("a", [[0.0, 0.0, 0.0, 10.0], [100.0, 0.0, 0.0, 30.0]]), Cloud("b")))
    grown = add_particles(scene, 0, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], 7.0)
    np.testing.assert_array_equal(grown.clouds[0].particles[2:], [[1.0, 2.0, 3.0, 7.0], [4.0, 5.0, 6.0, 7.0]])
    near_origin = particles_within(grown.clouds[0], (0.0, 0.0, 0.0), 9.0)
    assert near_origin.tolist() == [0, 2, 3]  # 7.5 and 8.8 m away; the one at 100 m stays
    erased = delete_particles(grown, 0, near_origin)
    np.testing.assert_array_equal(erased.clouds[0].particles, [[100.0, 0.0, 0.0, 30.0]])
    assert delete_particles(grown, 0, []) is grown  # nothing erased: no edit
    moved = translated(scene, 0, (0.0, 10.0, 0.0))
    np.testing.assert_array_equal(moved.clouds[0].centres, [[0.0, 10.0, 0.0], [100.0, 10.0, 0.0]])
    one = translated(scene, 0, (5.0, 0.0, 0.0), particle=1)
    np.testing.assert_array_equal(one.clouds[0].centres, [[0.0, 0.0, 0.0], [105.0, 0.0, 0.0]])
    resized = with_mean_radius(scene, 0, 40.0)
    np.testing.assert_allclose(resized.clouds[0].radii, [20.0, 60.0])  # the spread is kept
    assert scene.clouds[0].particles[1, 0] == 100.0  # the original is untouched
    with pytest.raises(ValueError, match="finite 3-vector"):
        translated(scene, 0, (np.nan, 0.0, 0.0))


def test_a_brush_scatters_in_its_ball_at_its_rate_the_same_for_the_same_seed():
    from cloudcore.scenes.editing import BrushStroke

    stroke = BrushStroke(seed=3, rate=50.0, interval_s=0.1)
    counts = [stroke.due(0.0)] + [stroke.due(0.03) for _ in range(10)]
    assert counts[0] == 5  # the press dabs at once
    # frames of 30 ms: a dab once a tenth of a second has passed, of 50/s times the time since the last
    assert counts[1:] == [0, 0, 0, 6, 0, 0, 0, 6, 0, 0]
    assert BrushStroke(seed=3, rate=50.0).due(5.0) == 5 and stroke.due(5.0) == 10  # a stall is capped
    dab = stroke.dab((100.0, 0.0, 0.0), 20.0, 2000)
    distances = np.linalg.norm(dab - [100.0, 0.0, 0.0], axis=1)
    assert distances.max() <= 20.0
    assert np.mean(distances < 10.0) == pytest.approx(1 / 8, abs=0.03)  # uniform in volume
    np.testing.assert_array_equal(
        BrushStroke(seed=3, rate=1.0).dab((0, 0, 0), 5.0, 4), BrushStroke(seed=3, rate=1.0).dab((0, 0, 0), 5.0, 4)
    )


def test_a_drag_follows_the_mouse_on_a_plane_through_the_grabbed_point():
    from cloudcore.scenes.editing import drag_offset, drag_plane_normal

    camera = Camera((0.0, 100.0, 0.0), (0.0, 100.0, -10.0), 60.0)
    grabbed = np.array([0.0, 0.0, -100.0])
    horizontal = drag_plane_normal(camera, screen=False)
    # the mouse moved so that the ray now meets the grabbed point's altitude 50 m farther
    offset = drag_offset(camera.position, np.array([0.0, -100.0, -150.0]) / np.hypot(100.0, 150.0), grabbed, horizontal)
    np.testing.assert_allclose(offset, [0.0, 0.0, -50.0], atol=1e-9)
    screen = drag_plane_normal(camera, screen=True)
    np.testing.assert_allclose(screen, [0.0, 0.0, 1.0], atol=1e-12)
    up = drag_offset(camera.position, np.array([0.0, 0.0, -1.0]), grabbed, screen)
    np.testing.assert_allclose(up, [0.0, 100.0, 0.0], atol=1e-9)  # in the screen plane it rises
    assert drag_offset(camera.position, np.array([0.0, 1.0, 0.0]), grabbed, horizontal) is None


def test_a_gesture_is_one_undo_step():
    from cloudcore.scenes.editing import translated

    scene = Scene(clouds=(Cloud("a", [[0.0, 0.0, 0.0, 10.0]]),))
    history = History(scene)
    history.begin_gesture()
    for step in range(1, 5):  # a drag re-applies its offset to the scene it started from
        history.apply(translated(scene, 0, (step, 0.0, 0.0)))
    history.end_gesture()
    assert history.current.clouds[0].particles[0, 0] == 4.0
    assert history.undo() and history.current is scene and not history.undo()
    assert history.redo() and history.current.clouds[0].particles[0, 0] == 4.0
    history.begin_gesture()
    history.end_gesture()  # a gesture that changed nothing leaves no step
    assert history.undo() and history.current is scene
    history.begin_gesture()
    history.apply(add_particle(scene, 0, (1.0, 1.0, 1.0)))
    assert history.in_gesture
    assert history.undo() and history.current is scene  # undo mid-gesture ends it first
    assert not history.in_gesture


def test_box_fill_and_presets_make_undoable_scenes():
    from cloudcore.artist.cloudgen import PRESETS, box_fill
    from cloudcore.scenes.editing import add_preset_cloud, fill_box

    scene = Scene(clouds=(Cloud("a", [[0.0, 0.0, 0.0, 10.0]]),))
    filled, index = fill_box(scene, 0, (100.0, 1000.0, 0.0), (400.0, 200.0, 300.0), 30.0, 300, seed=4)
    added = filled.clouds[0].particles[1:]
    assert index == 0 and 0 < len(added) <= 300
    np.testing.assert_array_equal(
        added, box_fill((-100.0, 900.0, -150.0), (300.0, 1100.0, 150.0), 30.0, 300, seed=4)
    )  # Wang's default cull: a third of the sprite size
    new, index = fill_box(scene, None, (0.0, 0.0, 0.0), (100.0, 100.0, 100.0), 10.0, 50, cull_distance=0.0)
    assert index == 1 and len(new.clouds[1].particles) == 50 and new.clouds[0] is scene.clouds[0]
    two = add_preset_cloud(add_preset_cloud(scene, "stratus", (0.0, 2000.0, 0.0)), "stratus", (0.0, 2000.0, 0.0))
    assert [c.name for c in two.clouds] == ["a", "stratus0", "stratus1"]
    assert two.clouds[1].optical_depth == PRESETS["stratus"].optical_depth
    with pytest.raises(ValueError, match="unknown cloud preset"):
        add_preset_cloud(scene, "fog", (0.0, 0.0, 0.0))
