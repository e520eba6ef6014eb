"""The in-cloud facing lock (Wang 2004, section 3.3) and the sprite corners built from it."""

import numpy as np
import pytest

from cloudcore.artist.facing import (
    CORNERS,
    FALLBACK_NORMAL,
    HORIZONTAL_NORMAL,
    LOCK_RADII,
    UNLOCK_RADII,
    FacingLocks,
    sprite_axes,
    sprite_corners,
)

# five sprites strung along x, a little off the camera's line so it passes beside their centres
CENTRES = np.array(
    [[0.0, 1000.0, 0.0], [120.0, 1010.0, 5.0], [260.0, 995.0, -8.0], [400.0, 1000.0, 12.0], [520.0, 1004.0, 0.0]]
)
RADII = np.array([60.0, 50.0, 80.0, 40.0, 70.0])
ROTATIONS = np.radians([0.0, 45.0, 170.0, 300.0, 90.0])


def fly(path: np.ndarray) -> list:
    """FacingState at each eye position of `path`, one update per position."""
    locks = FacingLocks(len(CENTRES))
    return [locks.update(eye, CENTRES, RADII) for eye in path]


def straight_path(steps: int = 400) -> np.ndarray:
    x = np.linspace(-200.0, 700.0, steps)
    return np.column_stack([x, np.full(steps, 1003.0), np.full(steps, 2.0)])


def test_locked_sprites_keep_their_orientation_while_the_camera_flies_through():
    path = straight_path()
    states = fly(path)
    locked = np.array([s.locked for s in states])  # (steps, sprites)
    assert np.all(locked.any(axis=0))  # every sprite was passed within half its radius
    corners = [sprite_corners(CENTRES, RADII, s.normals, ROTATIONS) for s in states]
    for step in range(1, len(path)):
        still = locked[step] & locked[step - 1]
        # the vertex data of a sprite that stays locked does not move by a bit
        np.testing.assert_array_equal(states[step].normals[still], states[step - 1].normals[still])
        np.testing.assert_array_equal(corners[step][still], corners[step - 1][still])
        moving = ~locked[step] & ~locked[step - 1]
        assert np.all(np.any(corners[step][moving] != corners[step - 1][moving], axis=(1, 2)))  # they turn
    for sprite in range(len(CENTRES)):
        steps = np.flatnonzero(locked[:, sprite])
        assert np.all(np.diff(steps) == 1)  # one stretch: locked once, unlocked once
        first = steps[0]
        to_eye = path[first] - CENTRES[sprite]
        np.testing.assert_allclose(states[first].normals[sprite], to_eye / np.linalg.norm(to_eye), atol=1e-15)
        assert np.linalg.norm(to_eye) < LOCK_RADII * RADII[sprite]
        assert not locked[-1, sprite]


def test_a_sprite_locks_within_half_its_radius_and_unlocks_beyond_the_hysteresis_band():
    centre, radius = CENTRES[:1], RADII[:1]
    locks = FacingLocks(1)
    assert not locks.update(centre[0] + [0.52 * radius[0], 0, 0], centre, radius).locked[0]  # not yet within 0.5 r
    assert locks.update(centre[0] + [0.49 * radius[0], 0, 0], centre, radius).locked[0]
    normal = locks.update(centre[0] + [0.45 * radius[0], 0, 0], centre, radius).normals[0].copy()
    # out to 0.54 r: still locked, same facing (a camera hovering at 0.5 r does not make it jump)
    for distance in (0.501, 0.499, 0.53, 0.5, 0.54):
        state = locks.update(centre[0] + [0.0, distance * radius[0], 0.0], centre, radius)
        assert state.locked[0]
        np.testing.assert_array_equal(state.normals[0], normal)
    state = locks.update(centre[0] + [0.0, 0.56 * radius[0], 0.0], centre, radius)
    assert not state.locked[0] and state.fade[0] == 1.0
    np.testing.assert_allclose(state.normals[0], [0.0, 1.0, 0.0], atol=1e-15)  # facing the eye again
    relocked = locks.update(centre[0] + [0.0, 0.4 * radius[0], 0.0], centre, radius)
    assert relocked.locked[0]
    np.testing.assert_allclose(relocked.normals[0], [0.0, 1.0, 0.0], atol=1e-15)  # a new lock, a new facing
    assert UNLOCK_RADII == pytest.approx(1.1 * LOCK_RADII)


def test_fade_falls_as_the_camera_swings_around_a_locked_sprite():
    centre, radius = CENTRES[2:3], RADII[2:3]
    locks = FacingLocks(1)
    reach = 0.3 * radius[0]
    angles = np.radians(np.arange(0.0, 181.0, 5.0))
    states = [locks.update(centre[0] + reach * np.array([np.cos(a), 0.0, np.sin(a)]), centre, radius) for a in angles]
    fade = np.array([s.fade[0] for s in states])
    assert all(s.locked[0] for s in states)
    assert fade[0] == 1.0
    before = angles < np.radians(90.0)
    assert np.all(np.diff(fade[before]) < 0.0)  # strictly falling up to edge-on
    assert np.all(fade[~before] == 0.0)  # gone from edge-on round to behind
    assert 0.4 < fade[angles == np.radians(60.0)][0] < 0.6
    assert fade[angles == np.radians(10.0)][0] > 0.95  # a small turn of the head barely dims it


def test_the_eye_at_a_sprite_centre_is_finite():
    centre, radius = CENTRES[:1], RADII[:1]
    fresh = FacingLocks(1).update(centre[0], centre, radius)  # never anywhere else
    assert fresh.locked[0]
    np.testing.assert_array_equal(fresh.normals[0], FALLBACK_NORMAL)
    assert np.isfinite(fresh.fade[0])
    locks = FacingLocks(1)
    approach = locks.update(centre[0] + [0.0, 0.0, 0.2 * radius[0]], centre, radius)
    at_centre = locks.update(centre[0], centre, radius)
    assert at_centre.locked[0] and np.all(np.isfinite(at_centre.normals)) and np.isfinite(at_centre.fade[0])
    np.testing.assert_array_equal(at_centre.normals[0], approach.normals[0])
    past = locks.update(centre[0] - [0.0, 0.0, 0.2 * radius[0]], centre, radius)
    assert past.fade[0] == 0.0  # passed through: the locked sprite is behind the eye
    corners = sprite_corners(centre, radius, at_centre.normals, [0.3])
    assert np.all(np.isfinite(corners))


def test_state_arrays_are_read_only_and_shapes_are_checked():
    locks = FacingLocks(len(CENTRES))
    state = locks.update([0.0, 1000.0, 10.0], CENTRES, RADII)
    assert state.locked.shape == (5,) and state.normals.shape == (5, 3) and state.fade.shape == (5,)
    with pytest.raises(ValueError):
        state.normals[0, 0] = 1.0
    with pytest.raises(ValueError, match="centres"):
        locks.update([0.0, 0.0, 0.0], CENTRES[:4], RADII[:4])
    with pytest.raises(ValueError, match="finite"):
        locks.update([0.0, np.nan, 0.0], CENTRES, RADII)
    far = locks.update([1.7e308, -1.7e308, 0.0], CENTRES, RADII)  # beyond float range: far, not broken
    assert not far.locked.any() and np.all(np.isfinite(far.normals))


def test_sprite_axes_are_upright_and_orthonormal():
    rng = np.random.default_rng(6)
    normals = rng.normal(size=(200, 3))
    normals = np.concatenate(
        [normals / np.linalg.norm(normals, axis=1, keepdims=True), [HORIZONTAL_NORMAL, [0.0, -1.0, 0.0]]]
    )
    rights, ups = sprite_axes(normals)
    for a, b in ((rights, ups), (rights, normals), (ups, normals)):
        np.testing.assert_allclose(np.einsum("ij,ij->i", a, b), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(rights, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.cross(rights, ups), normals, atol=1e-12)  # right-handed, facing the viewer
    assert np.all(ups[:200, 1] >= 0.0) and np.all(rights[:200, 1] == 0.0)  # up is up, right is level
    np.testing.assert_allclose(ups[200], [0.0, 0.0, -1.0])  # a flat quad seen from above: north is up
    np.testing.assert_allclose(rights[200], [1.0, 0.0, 0.0])


def test_sprite_corners_are_a_rotated_square_of_side_two_radii():
    centre, radius = np.array([[10.0, 500.0, -20.0]]), np.array([30.0])
    normal = np.array([[0.0, 0.0, 1.0]])  # the eye on +z: right is +x, up is +y
    upright = sprite_corners(centre, radius, normal, [0.0])[0]
    np.testing.assert_allclose(upright - centre, 30.0 * np.column_stack([CORNERS, np.zeros(4)]), atol=1e-12)
    quarter = sprite_corners(centre, radius, normal, [np.pi / 2])[0]
    # counter-clockwise: the lower left corner goes to the lower right
    np.testing.assert_allclose(quarter[0] - centre[0], [30.0, -30.0, 0.0], atol=1e-12)
    edges = np.cross(quarter[1] - quarter[0], quarter[2] - quarter[1])
    assert edges @ normal[0] > 0  # counter-clockwise seen from the eye: front-facing
