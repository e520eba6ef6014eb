"""The plan at scale: its decisions are arrays, a unit costs Python time only where it is drawn, and what the ring
holds keeps no impostor of its own."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.lod.impostors import parallax_errors_deg
from cloudcore.lod.plan import LodState, plan_frame
from cloudcore.lod.plan.draw_items import DrawItem, draw_items
from cloudcore.lod.plan.pricing import panel_pixels, ring_translation_error
from cloudcore.lod.plan.unit_plans import FULL, KINDS, UnitPlans
from cloudcore.lod.ring import (
    SEGMENTS,
    RingGeneration,
    RingState,
    frames_to_show,
    panel_spans,
    plan_ring,
    ring_candidates,
    ring_members,
    segments_of,
)
from cloudcore.lod.splitting import layer_bounds, layer_sort_key
from cloudcore.lod.units import LodUnits
from cloudcore.model.scene import Camera
from cloudcore.model.settings import RenderSettings
from cloudcore.world.camera import frustum_planes, projection_matrix, spheres_in_frustum, view_matrix

VIEWPORT = (640, 480)
CAMERA = Camera((0.0, 1000.0, 0.0), (1000.0, 1000.0, 300.0), 60.0)


def scattered_units(count: int, seed: int = 3) -> LodUnits:
    """`count` clouds of 200 particles scattered over 40 km square at cloud height."""
    rng = np.random.default_rng(seed)
    centres = np.column_stack(
        [rng.uniform(-20e3, 20e3, count), rng.uniform(850.0, 1150.0, count), rng.uniform(-20e3, 20e3, count)]
    )
    radii = rng.uniform(80.0, 160.0, count)
    return LodUnits.of_spheres(centres, radii, radii / 8.0, [200.0] * count, 200.0 * (radii / 8.0) ** 2)


class CountingKeys(tuple):
    """Lighting keys that count the clouds whose key the plan looks up one by one."""

    def __new__(cls, count):
        keys = super().__new__(cls, ((cloud, None, 1.0) for cloud in range(count)))
        keys.looked_up = set()
        return keys

    def __getitem__(self, cloud):
        self.looked_up.add(cloud)
        return super().__getitem__(cloud)


@pytest.mark.parametrize("mode", ["full", "impostor", "auto"])
def test_every_unit_s_kind_is_what_its_sphere_and_the_ring_say(mode):
    units = scattered_units(3000)
    settings = RenderSettings(mode=mode)
    state = LodState()
    for _ in range(SEGMENTS + settings.ring_fade_frames + 1):  # the ring built and faded in
        frame = plan_frame(units, CAMERA, VIEWPORT, settings, state, 1)
        state = frame.state
    width, height = VIEWPORT
    planes = frustum_planes(projection_matrix(60.0, width / height) @ view_matrix(CAMERA))
    visible = spheres_in_frustum(planes, units.centres, units.radii)
    in_ring = ring_members(units.centres, units.radii, np.array(CAMERA.position), settings) & (mode != "full")
    kinds = np.array([cloud.kind for cloud in frame.clouds])
    assert np.all(kinds[in_ring] == "ring")
    assert np.all(kinds[~in_ring & ~visible] == "culled")
    assert np.all(np.isin(kinds[~in_ring & visible], ("full", "impostor", "crossfade")))
    assert in_ring.sum() > 2000 or mode == "full"  # most of the scene is in the ring, as at Harris's scale
    by_kind = frame.stats().clouds_by_kind
    assert by_kind == {kind: int(np.sum(kinds == kind)) for kind in KINDS}
    assert sorted(frame.draw_order) == sorted(np.flatnonzero(np.isin(kinds, ("full", "impostor", "crossfade"))))


@pytest.mark.parametrize("mode", ["full", "impostor", "auto"])
def test_only_the_units_drawn_on_their_own_have_their_lighting_keys_looked_up(mode):
    units = scattered_units(3000)
    settings = RenderSettings(mode=mode)
    state, looked_up = LodState(), set()
    for _ in range(SEGMENTS + settings.ring_fade_frames + 3):
        keys = CountingKeys(len(units.radii))
        frame = plan_frame(units, CAMERA, VIEWPORT, settings, state, keys)
        state, looked_up = frame.state, keys.looked_up
    drawn = {cloud for index in frame.draw_order for cloud in units.members[index]}
    assert looked_up <= drawn and (len(drawn) < 200 or mode == "full")  # the ring holds the rest


def test_a_unit_the_ring_shows_whole_keeps_no_impostor_and_one_handed_back_is_made_anew():
    units = scattered_units(400)
    settings = RenderSettings(mode="impostor")
    first = plan_frame(units, CAMERA, VIEWPORT, settings, LodState(), 1)
    state = first.state
    made_first = set(state.records)
    for _ in range(SEGMENTS + settings.ring_fade_frames + 1):
        frame = plan_frame(units, CAMERA, VIEWPORT, settings, state, 1)
        state = frame.state
    in_ring = {frame.clouds.members[i] for i in frame.clouds.indices_of("ring")}
    assert in_ring & made_first, "the ring took clouds that had impostors of their own"
    assert not in_ring & set(state.records)
    # the ring off: every cloud is drawn on its own again, those it held from impostors made anew
    handed_back = plan_frame(units, CAMERA, VIEWPORT, RenderSettings(mode="impostor", ring_radius=math.inf), state, 1)
    reasons = {handed_back.clouds.members[i]: reason for i, reason in handed_back.clouds.regenerate.items()}
    assert {reasons.get(members) for members in in_ring if members in reasons} == {"new"}


def test_a_ring_candidate_s_impostor_lasts_until_the_ring_being_built_takes_it():
    settings = RenderSettings()
    still = np.zeros(3)
    assert frames_to_show(RingState(), still, settings) == SEGMENTS + settings.ring_fade_frames
    units = scattered_units(400)
    frame = plan_frame(units, CAMERA, VIEWPORT, settings, LodState(), 1)
    building = frame.state.ring
    assert building.pending is not None and building.built == 1
    assert frames_to_show(building, still, settings) == SEGMENTS - 1 + settings.ring_fade_frames
    assert frames_to_show(RingState(current=building.pending), still, settings) == math.inf


@pytest.mark.parametrize("metres_a_frame", [0.0, 5.0, 20.0, 60.0, 150.0, 400.0, 5000.0])
def test_the_frames_a_ring_takes_to_show_are_those_plan_ring_takes_at_the_eye_s_pace(metres_a_frame):
    """The candidates' impostor lifetimes are capped by `frames_to_show`: it counts the frames the ring's own
    plan takes, at Wang's segment a frame and fade for a slow eye and faster for a fast one (down to one frame)."""
    settings = RenderSettings()
    units = scattered_units(300)
    ids = units.members
    step = np.array([metres_a_frame, 0.0, 0.0])
    expected = frames_to_show(RingState(), step, settings)
    state, frames = RingState(), 0
    while state.current is None:
        ring = plan_ring(
            state,
            units.centres,
            units.radii,
            CAMERA.position,
            settings,
            (1,) * len(ids),
            ids,
            frozenset(ids),
            (256, 64),
            step=step,
        )
        state, frames = ring.state, frames + 1
        assert frames <= SEGMENTS + settings.ring_fade_frames
    assert frames == expected
    # half the 600 m rebuild distance over Wang's 16 frames: 18.75 m a frame
    assert (frames == SEGMENTS + settings.ring_fade_frames) == (metres_a_frame <= 18.75)
    assert (frames == 1) == (metres_a_frame > 150.0)  # half the rebuild distance in under two frames


def test_the_draw_items_are_the_drawn_units_layers_and_objects_far_to_near_as_a_sort_of_records_would_give():
    rng = np.random.default_rng(5)
    count = 40
    distances = np.round(rng.uniform(100.0, 500.0, count), 0)  # ties on purpose
    radii = rng.uniform(20.0, 60.0, count)
    object_centres = rng.uniform(-500.0, 500.0, (3, 3))
    eye = np.zeros(3)
    splits, split_objects = {}, {}
    for index in (3, 7, 21):
        objects = tuple(int(o) for o in rng.choice(3, size=2, replace=False))
        splits[index] = tuple(sorted((float(np.linalg.norm(object_centres[o])) for o in objects), reverse=True))
        split_objects[index] = objects
    kinds = np.full(count, FULL, dtype=np.int8)
    plans = UnitPlans(
        kinds,
        distances,
        tuple((i,) for i in range(count)),
        np.ones(count, int),
        splits=splits,
        split_objects=split_objects,
    )
    order = tuple(int(i) for i in np.argsort(-distances, kind="stable"))
    items = draw_items(plans, order, radii, object_centres, np.ones(3, dtype=bool), eye)
    expected = []
    for index in order:
        cut = splits.get(index, ())
        for layer in range(len(cut) + 1):
            near, far = layer_bounds(cut, layer)
            depth = layer_sort_key(near, far, float(distances[index]), radii[index]) if cut else float(distances[index])
            expected.append(DrawItem("cloud", index, float(depth), layer, near, far))
    for o in sorted({o for objects in split_objects.values() for o in objects}):
        distance = float(np.linalg.norm(object_centres[o] - eye))
        expected.append(DrawItem("object", o, distance, near=distance, far=distance))
    expected.sort(key=lambda item: (-item.depth, -item.far, item.kind != "object"))
    assert list(items) == expected
    assert items.objects == tuple(item.index for item in expected if item.kind == "object")


def test_ring_panels_fill_the_box_of_their_clouds_on_the_screen_not_the_sum_of_their_quads():
    """A panel is one layer cropped to its clouds: twenty far clouds stacked on the horizon in one segment fill
    about their box, a strip, where their quads summed would be several times it; clouds few and far apart fill
    their quads' sum; and no panel counts more than the screen."""
    eye = np.zeros(3)
    camera = Camera(tuple(eye), (0.0, 0.0, -1000.0), 60.0)
    view_projection = projection_matrix(camera.fov_y_deg, 640 / 480) @ view_matrix(camera)
    crowd = np.column_stack([np.linspace(1700.0, 2300.0, 20), np.full(20, 150.0), np.full(20, -6000.0)])  # 16-21 deg
    quads = np.full(20, 60.0**2)  # each 60 px across, overlapping their neighbours
    strip = panel_pixels(crowd, segments_of(crowd, eye), quads, view_projection, (640, 480))
    assert strip < 0.5 * np.sum(quads)
    # 600 m across at 6 km is 41.6 px on this screen: their box is that and a quad's side across, a quad high
    assert strip == pytest.approx((41.57 + 60.0) * 60.0, rel=1e-3)
    apart = np.array([[-2500.0, 150.0, -6000.0], [2500.0, 150.0, -6000.0]])  # two segments, one cloud each
    assert panel_pixels(apart, segments_of(apart, eye), [900.0, 900.0], view_projection, (640, 480)) == 1800.0
    behind = np.array([[0.0, 0.0, 6000.0]])
    assert panel_pixels(behind, segments_of(behind, eye), [1e9], view_projection, (640, 480)) == 640 * 480


def test_the_ring_s_largest_parallax_error_is_its_whole_ring_s_whatever_the_step():
    """`ring_translation_error` measures the clouds whose error grows fastest and bounds the rest: over a ring of
    2,000 clouds and steps from centimetres to past the nearest cloud, it is the maximum over every cloud."""
    rng = np.random.default_rng(11)
    count = 2000
    angles, ranges = rng.uniform(0.0, 2.0 * np.pi, count), rng.uniform(4000.0, 30000.0, count)
    centres = np.column_stack([ranges * np.sin(angles), rng.uniform(800.0, 2500.0, count), -ranges * np.cos(angles)])
    radii = rng.uniform(50.0, 900.0, count)
    eye = (0.0, 1000.0, 0.0)
    generation = RingGeneration(
        eye, 4000.0, np.arange(count), np.zeros(count, object), frozenset(), (), spheres=(centres, radii)
    )
    generation = dataclasses.replace(generation, members=frozenset((i,) for i in range(count)))
    # and one whose fastest clouds (large, near, due north) see a step due north end on: the largest error is
    # another cloud's, which only the bound can send the measure to
    north = np.column_stack([rng.uniform(-50.0, 50.0, 100), np.full(100, 1000.0), rng.uniform(-5000.0, -4500.0, 100)])
    lined_up = RingGeneration(
        eye,
        4000.0,
        np.arange(count + 100),
        np.zeros(count + 100, object),
        frozenset((i,) for i in range(count + 100)),
        (),
        spheres=(np.concatenate([north, centres]), np.concatenate([np.full(100, 1500.0), radii])),
    )
    for ring, directions in ((generation, rng.normal(size=(4, 3))), (lined_up, [(0.0, 0.0, -1.0)])):
        for step in (0.0, 0.05, 3.0, 120.0, 2500.0, 6000.0):
            for direction in directions:
                now = np.asarray(eye) + step * np.asarray(direction) / np.linalg.norm(direction)
                whole = float(np.max(parallax_errors_deg(*ring.panel_spans(), eye, now)))
                assert ring_translation_error(ring, now) == whole


@pytest.mark.parametrize("with_heights", [False, True])
def test_the_ring_s_candidates_held_by_their_slack_are_ring_members_at_every_step(with_heights):
    """`ring_candidates` asks again only of the units whose answer may have changed since it asked all: along a
    walk of small and large steps, past the ring's radius and its band's edges for many clouds, its answer is
    `ring_members`' at every step, and a step of centimetres asks nothing of the units it holds the answer of."""
    rng = np.random.default_rng(5)
    count = 3000
    settings = RenderSettings(mode="auto")
    # clouds crowded about the ring's radius and its elevation band's edge, seen from the eye at 1000 m
    horizontal = settings.ring_radius * rng.uniform(0.8, 1.6, count)
    angles = rng.uniform(0.0, 2.0 * np.pi, count)
    band = np.tan(np.radians(settings.ring_elevation_deg))
    heights = 1000.0 + horizontal * band * rng.uniform(-1.3, 1.3, count)
    centres = np.column_stack([horizontal * np.sin(angles), heights, -horizontal * np.cos(angles)])
    radii = rng.uniform(20.0, 0.3 * settings.ring_radius, count)
    radii[:10] = 0.0  # empty units: never in the ring
    reach = np.column_stack([heights - 0.3 * radii, heights + 0.3 * radii]) if with_heights else None
    units = dataclasses.replace(
        LodUnits.of_spheres(centres, radii, radii / 8.0, [200.0] * count, 200.0 * (radii / 8.0) ** 2), heights=reach
    )
    eye = np.array([0.0, 1000.0, 0.0])
    held = ring_candidates(None, units, eye, settings)
    assert np.array_equal(held.members, ring_members(centres, radii, eye, settings, reach))
    still = ring_candidates(held, units, eye + 0.01, settings)
    assert still.slack is held.slack and np.array_equal(still.members, held.members)
    changed = 0
    for step in [0.5, 3.0, 20.0, 80.0, 300.0] * 8:
        direction = rng.normal(size=3)
        eye = eye + step * direction / np.linalg.norm(direction)
        before = held.members
        held = ring_candidates(held, units, eye, settings)
        assert np.array_equal(held.members, ring_members(centres, radii, eye, settings, reach))
        changed += int(np.count_nonzero(held.members != before))
    assert changed > 50  # the walk did move clouds into and out of the ring


def test_a_panel_span_reaches_from_the_panel_to_the_cloud_s_far_side_and_its_parallax_is_the_panel_s_shift():
    """A cloud 12 km off along the middle of a segment of a ring of 4 km: its panel's point is 4 km along the same
    ray, so its span runs from there to the sphere's far side; an eye stepped 100 m across sees the panel's point
    and the cloud's far side 100 (1/4000 - 1/12200) radians apart, the shift a flat panel shows, which the
    cloud's own parallax (its sphere's near and far points) is a small part of.  A cloud astride the panel spans
    its own sphere; off the segment's middle, the ray meets the flat panel farther out."""
    eye = np.array([0.0, 1000.0, 0.0])

    def along(azimuth_deg: float, distance: float) -> np.ndarray:
        azimuth = math.radians(azimuth_deg)
        return eye + distance * np.array([math.sin(azimuth), 0.0, -math.cos(azimuth)])

    centres, radii = np.array([along(22.5, 12000.0), along(22.5, 4050.0), along(40.0, 12000.0)]), np.full(3, 200.0)
    spans, span_radii = panel_spans(centres, radii, eye, 4000.0)
    assert spans[0] == pytest.approx(along(22.5, 8100.0)) and span_radii[0] == pytest.approx(4100.0)
    assert spans[1] == pytest.approx(centres[1]) and span_radii[1] == pytest.approx(radii[1])
    near_end = np.linalg.norm(spans[2] - eye) - span_radii[2]
    assert near_end == pytest.approx(4000.0 / math.cos(math.radians(40.0 - 22.5)))
    across = eye + 100.0 * np.array([math.cos(math.radians(22.5)), 0.0, math.sin(math.radians(22.5))])
    shift = math.degrees(100.0 * (1.0 / 4000.0 - 1.0 / 12200.0))
    assert parallax_errors_deg(spans[:1], span_radii[:1], eye, across)[0] == pytest.approx(shift, rel=1e-3)
    assert parallax_errors_deg(centres[:1], radii[:1], eye, across)[0] < 0.05 * shift
