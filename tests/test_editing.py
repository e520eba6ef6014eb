"""Editing as pure functions: picking, adding particles and clouds, undo and redo."""

import numpy as np
import pytest

from cloudcore.editing import History, add_cloud, add_particle, delete_cloud, pick_ray, point_at_altitude
from cloudcore.scene import Camera, Cloud, Scene


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
    from cloudcore.impostors import translation_error_deg
    from cloudcore.navigation import moved, orbited, turned

    camera = Camera((0.0, 100.0, 500.0), (0.0, 100.0, 0.0), 60.0)
    around = orbited(camera, 1.0)
    assert translation_error_deg(camera.look_at, camera.position, around.position) == pytest.approx(1.0)
    assert np.linalg.norm(np.subtract(around.position, around.look_at)) == pytest.approx(500.0)
    ahead = moved(camera, forward=100.0)
    np.testing.assert_allclose(ahead.position, [0.0, 100.0, 400.0], atol=1e-9)
    np.testing.assert_allclose(np.subtract(ahead.look_at, ahead.position), [0.0, 0.0, -500.0], atol=1e-9)  # look-at moves along
    up = turned(camera, 0.0, 200.0)  # clamped short of straight up
    assert 0.0 < np.subtract(up.look_at, up.position)[1] < 500.0
