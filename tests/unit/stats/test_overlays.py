"""Screen outlines of impostors and ring panels, from frame plans without GL."""

import math

import numpy as np
import pytest

from cloudcore.lod.impostors import screen_size_px
from cloudcore.lod.plan import LodState, plan_frame
from cloudcore.lod.units import LodUnits
from cloudcore.model.scene import Camera
from cloudcore.model.settings import RenderSettings
from cloudcore.scenes.editing import pick_ray
from cloudcore.stats.overlays import clip_to_near, impostor_outlines, ring_outlines, screen_polygon, to_pixels

VIEWPORT = (640, 480)
CAMERA = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 60.0)


def test_a_projected_point_is_where_the_pick_ray_through_its_pixel_goes():
    camera = Camera((10.0, 200.0, 30.0), (400.0, 350.0, -900.0), 50.0)
    points = np.array([[300.0, 260.0, -700.0], [900.0, 100.0, -2000.0], [0.0, 200.0, 1000.0]])
    pixels, in_front = to_pixels(points, camera, VIEWPORT)
    assert in_front.tolist() == [True, True, False]  # the last is behind the eye
    for point, (x, y) in zip(points[:2], pixels[:2]):
        origin, direction = pick_ray(camera, VIEWPORT[0] / VIEWPORT[1], x / VIEWPORT[0], y / VIEWPORT[1])
        towards = (point - origin) / np.linalg.norm(point - origin)
        np.testing.assert_allclose(direction, towards, atol=1e-12)


def test_a_polygon_is_cut_at_the_near_plane():
    square = np.array([[-1.0, -1.0, 5.0], [1.0, -1.0, 5.0], [1.0, 1.0, -5.0], [-1.0, 1.0, -5.0]])  # eye space
    clipped = clip_to_near(square, 1.0)
    assert len(clipped) == 4 and clipped[:, 2].max() == pytest.approx(-1.0)
    np.testing.assert_allclose(clipped[clipped[:, 2] == -1.0][:, 1], [0.2, 0.2])  # 6 of the 10 m to the plane
    assert clip_to_near(square + [0.0, 0.0, 10.0], 1.0) is None
    ahead = screen_polygon([[-1.0, -1.0, -10.0], [1.0, -1.0, -10.0], [1.0, 1.0, -10.0]], CAMERA, VIEWPORT)
    focal = 1.0 / math.tan(math.radians(30.0))  # a tenth of the way to the edge of a 60-degree view, times f
    np.testing.assert_allclose(
        ahead, 0.5 * np.array(VIEWPORT) * (1.0 + 0.1 * focal * np.array([[-3 / 4, 1.0], [3 / 4, 1.0], [3 / 4, -1.0]]))
    )


def test_an_impostor_outline_is_its_quad_on_screen():
    distance, radius = 3000.0, 200.0
    centres, radii = np.array([[0.0, 0.0, -distance], [0.0, 0.0, -15.0]]), np.array([radius, 10.0])
    # the far cloud's splats fill more than its quad, the near one has none to draw: impostor, full
    units = LodUnits.of_spheres(centres, radii, particle_counts=[3000, 0], radius_squares=[3000 * 40.0**2, 0.0])
    plan = plan_frame(units, CAMERA, VIEWPORT, RenderSettings(ring_radius=math.inf), LodState(), 1)
    assert [c.kind for c in plan.clouds] == ["impostor", "full"]
    (outline,) = impostor_outlines(plan, CAMERA, VIEWPORT)  # the full cloud has none
    assert (outline.kind, outline.index) == ("impostor", 0)
    side = screen_size_px(radius, distance, VIEWPORT[1], CAMERA.fov_y_deg)
    np.testing.assert_allclose(np.ptp(outline.points, axis=0), [side, side], rtol=1e-9)
    np.testing.assert_allclose(outline.points.mean(axis=0), [320.0, 240.0], atol=1e-9)


def test_the_ring_outlines_are_the_panels_in_front_of_the_eye():
    settings = RenderSettings(mode="impostor", ring_radius=1000.0)  # auto mode would price the ring
    angles = np.radians(np.arange(0.0, 360.0, 30.0))
    centres = np.column_stack([3000.0 * np.sin(angles), np.zeros(len(angles)), -3000.0 * np.cos(angles)])
    radii = np.full(len(angles), 100.0)
    units = LodUnits.of_spheres(centres, radii)
    state, plan = LodState(), None
    for _ in range(8 + settings.ring_fade_frames):  # one segment a frame, then the fade in
        plan = plan_frame(units, CAMERA, VIEWPORT, settings, state, 1)
        state = plan.state
    assert plan.ring.draws and all(c.kind == "ring" for c in plan.clouds)
    outlines = ring_outlines(plan, CAMERA, VIEWPORT, settings.ring_elevation_deg)
    # looking along a panel boundary (-z) with a 60-degree field: two panels ahead, and the two beside
    # them that the near plane cuts; the four behind are gone
    assert sorted(o.index for o in outlines) == [0, 1, 6, 7]
    xs = np.concatenate([o.points[:, 0] for o in outlines])
    assert xs.min() < 0.0 and xs.max() > VIEWPORT[0]  # together they span the view
    ahead = [o for o in outlines if o.index in (0, 7)]
    for outline in ahead:  # symmetric about the horizon; the panel reaches 30 degrees up, the view 30 too
        ys = outline.points[:, 1]
        assert ys.min() + ys.max() == pytest.approx(VIEWPORT[1], abs=1e-6)
        assert ys.min() <= 0.0
    assert (
        ring_outlines(
            plan_frame(units, CAMERA, VIEWPORT, RenderSettings(ring_radius=math.inf), LodState(), 1),
            CAMERA,
            VIEWPORT,
            30.0,
        )
        == []
    )
