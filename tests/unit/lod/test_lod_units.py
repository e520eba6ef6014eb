"""Units of the level of detail without GL: interpenetrating clouds grouped, and one impostor for a group."""

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from cloudcore.lod.costs import SPRITE_FRAGMENT_COST, CostModel
from cloudcore.lod.impostors import parallax_errors_deg
from cloudcore.lod.plan import LodState, plan_frame
from cloudcore.lod.units import (
    FIELD_CELL_DETAIL_SCALE,
    SAMPLE_PER_CLOUD,
    LodUnits,
    SplatSample,
    interpenetrating_groups,
    lod_units,
)
from cloudcore.model.scene import Camera, splats_bounding_sphere
from cloudcore.model.settings import RenderSettings

RNG = np.random.default_rng(11)


def blob(centre, count=300, spread=40.0, radius=12.0):
    points = RNG.normal(size=(count, 3)) * spread + np.asarray(centre, dtype=float)
    return points, np.full(count, radius)


class Packed:
    """The parts of a `ParticleBuffer` that `lod_units` reads."""

    def __init__(self, blobs, sprites=()):
        """`sprites`: the blobs drawn as atlas sprites, the rest Gaussian splats."""
        self.centres = np.concatenate([b[0] for b in blobs])
        self.radii = np.concatenate([b[1] for b in blobs])
        self.cloud_starts = np.concatenate([[0], np.cumsum([len(b[1]) for b in blobs])])
        spheres = [splats_bounding_sphere(*b) for b in blobs]
        self.bounding_centres = np.array([s[0] for s in spheres])
        self.bounding_radii = np.array([s[1] for s in spheres])
        self.finest_radii = np.array([b[1].min() for b in blobs])
        cells = [np.full(len(b[1]), 0 if i in sprites else -1, dtype=np.int32) for i, b in enumerate(blobs)]
        self.styles = SimpleNamespace(sprite_index=np.concatenate(cells))


# two clouds whose particles mingle, one whose bounding sphere grazes theirs but whose splats stay apart,
# and one far off
CLOUDS = Packed([blob((0, 0, 0)), blob((60, 0, 0)), blob((330, 0, 0)), blob((3000, 0, 0))])


def test_clouds_whose_splats_interpenetrate_are_grouped_and_the_rest_stand_alone():
    groups = interpenetrating_groups(
        CLOUDS.centres, CLOUDS.radii, CLOUDS.cloud_starts, CLOUDS.bounding_centres, CLOUDS.bounding_radii
    )
    assert groups == ((0, 1), (2,), (3,))
    gap = np.linalg.norm(CLOUDS.bounding_centres[1] - CLOUDS.bounding_centres[2])
    assert gap < CLOUDS.bounding_radii[1] + CLOUDS.bounding_radii[2]  # the spheres alone would have grouped it


def test_a_group_s_sphere_encloses_every_splat_of_its_clouds():
    units = lod_units(CLOUDS)
    assert units.members == ((0, 1), (2,), (3,))
    group = np.arange(CLOUDS.cloud_starts[0], CLOUDS.cloud_starts[2])
    reach = np.linalg.norm(CLOUDS.centres[group] - units.centres[0], axis=1) + CLOUDS.radii[group]
    assert reach.max() <= units.radii[0] + 1e-9
    assert units.particle_counts.tolist() == [600, 300, 300]
    np.testing.assert_allclose(units.radius_squares, [600 * 144.0, 300 * 144.0, 300 * 144.0])
    assert lod_units(CLOUDS, group=False).members == ((0,), (1,), (2,), (3,))


def test_a_group_shares_one_impostor_made_from_all_its_particles():
    units = lod_units(CLOUDS)
    camera = Camera((0.0, 0.0, 2000.0), (0.0, 0.0, 0.0), 60.0)
    first = plan_frame(units, camera, (640, 480), RenderSettings(mode="impostor", ring_radius=np.inf), LodState(), 1)
    grouped = first.clouds[0]
    assert (grouped.kind, grouped.members, grouped.regenerate) == ("impostor", (0, 1), "new")
    assert set(first.records) == {(0, 1), (2,)}  # the far cloud is out of view
    stats = first.stats()
    assert stats.clouds_by_kind["impostor"] == 3 and stats.units == 3 and stats.units_grouped == 1
    # one cloud of the group changes: the group's impostor is remade, the other unit's is not
    relit = plan_frame(
        units, camera, (640, 480), RenderSettings(mode="impostor", ring_radius=np.inf), first.state, (1, 2, 1, 1)
    )
    assert [c.regenerate for c in relit.clouds[:2]] == ["lights", None]


def test_a_regrouping_drops_the_impostors_of_units_that_no_longer_exist():
    camera = Camera((0.0, 0.0, 2000.0), (0.0, 0.0, 0.0), 60.0)
    settings = RenderSettings(mode="impostor", ring_radius=np.inf)
    grouped = plan_frame(lod_units(CLOUDS), camera, (640, 480), settings, LodState(), 1)
    apart = plan_frame(lod_units(CLOUDS, group=False), camera, (640, 480), settings, grouped.state, 1)
    assert [c.regenerate for c in apart.clouds[:3]] == ["new", "new", None]
    assert set(apart.records) == {(0,), (1,), (2,)}


def test_a_cloud_field_s_cells_impostors_are_made_finer_where_their_detail_bounds_them():
    """Two alike clouds 500 m off, the second a cloud field's cell (past `groupable`): where the finest splat bounds
    the texture, below what the screen asks, the cell's is twice as fine (`FIELD_CELL_DETAIL_SCALE`); its few
    splats cost little to remake, and its magnified splats lost their lumps to the coarser one."""
    points = np.random.default_rng(5).normal(size=(300, 3)) * 40.0  # the module's RNG left to the other tests
    twins = Packed([(points + (x, 0.0, 0.0), np.full(300, 12.0)) for x in (-150.0, 150.0)])
    units = lod_units(twins, groupable=1)
    assert units.members == ((0,), (1,)) and units.texel_scales.tolist() == [1.0, FIELD_CELL_DETAIL_SCALE]
    camera = Camera((0.0, 0.0, 500.0), (0.0, 0.0, 0.0), 60.0)
    settings = RenderSettings(mode="impostor", ring_radius=np.inf, impostor_max_size=4096)
    authored, cell = plan_frame(units, camera, (640, 480), settings, LodState(), 1).clouds
    on_screen = plan_frame(
        units, camera, (640, 480), dataclasses.replace(settings, impostor_detail_texels=0.0), LodState(), 1
    ).clouds
    assert authored.texture_size < cell.texture_size < on_screen[1].texture_size
    assert cell.texture_size / authored.texture_size == pytest.approx(FIELD_CELL_DETAIL_SCALE, rel=0.2)
    # every unit of a scene without a field keeps the setting's detail
    assert lod_units(twins).texel_scales.tolist() == [1.0, 1.0]


def test_units_of_spheres_are_one_cloud_each():
    units = LodUnits.of_spheres(np.zeros((2, 3)), [1.0, 2.0])
    assert units.members == ((0,), (1,)) and len(units.radii) == 2
    assert dataclasses.is_dataclass(units)


def fly(units, eyes, settings, costs=CostModel(), state=None):
    """Plan a frame from each eye in turn (looking at the origin); the plans."""
    plans, state = [], state or LodState()
    for eye in eyes:
        plan = plan_frame(units, Camera(tuple(eye), (0.0, 0.0, 0.0), 60.0), (640, 480), settings, state, 1, costs=costs)
        plans.append(plan)
        state = plan.state
    return plans


def sideways(start, step, frames):
    return [np.add(start, (step * k, 0.0, 0.0)) for k in range(frames)]


AUTO = RenderSettings(ring_radius=np.inf)


def touching(gap: float) -> Packed:
    """Two clouds `gap` apart whose splats meet halfway only, and one far off: one group twice a cloud's size."""
    left, right = blob((0, 0, 0), spread=20.0), blob((gap, 0, 0), spread=20.0)
    bridge = [np.array([[0.5 * gap - 4.0, 0.0, 0.0]]), np.array([[0.5 * gap + 4.0, 0.0, 0.0]])]
    return Packed(
        [
            (np.concatenate([left[0], bridge[0]]), np.append(left[1], 12.0)),
            (np.concatenate([right[0], bridge[1]]), np.append(right[1], 12.0)),
            blob((3000, 0, 0)),
        ]
    )


def test_a_moving_eye_plans_a_group_apart_where_its_clouds_impostors_cost_less():
    units = lod_units(touching(240.0))
    assert units.members[0] == (0, 1) and units.radii[0] > 1.7 * units.clouds.radii.max()
    # moving, the group's larger sphere passes the tolerance sooner, and is remade every particle at a time
    plans = fly(units, sideways((0.0, 0.0, 800.0), 6.0, 40), AUTO)
    assert plans[0].units.members[0] == (0, 1)  # first seen: nothing moves yet, the group is the cheaper
    apart = next(k for k, plan in enumerate(plans) if (0, 1) in plan.state.opened)
    opening = plans[apart]
    assert opening.units.members[:2] == ((0,), (1,))  # in place of the group
    # it opened where the group's impostor was due anyway: past the tolerance, remade from this eye otherwise
    assert plans[apart - 1].clouds[0].members == (0, 1)
    held = plans[apart - 1].records[(0, 1)]
    parallax = parallax_errors_deg(units.centres[:1], units.radii[:1], held.eye, np.asarray(opening.state.eye))
    assert parallax[0] > opening.tolerance_deg
    assert [c.regenerate for c in opening.clouds[:2]] == ["new", "new"]
    assert (0, 1) not in opening.records  # its texture goes back to the pool
    assert all((0, 1) in plan.state.opened for plan in plans[apart:])  # while it moves, it stays apart


def test_a_group_apart_closes_once_the_eye_stops_and_only_auto_mode_opens_one():
    units = lod_units(touching(240.0))
    moving = fly(units, sideways((0.0, 0.0, 800.0), 6.0, 40), AUTO)
    assert (0, 1) in moving[-1].state.opened
    still = fly(units, [moving[-1].state.eye] * 3, AUTO, state=moving[-1].state)
    assert (0, 1) not in still[-1].state.opened and still[-1].units.members[0] == (0, 1)
    for settings in (
        dataclasses.replace(AUTO, mode="impostor"),
        dataclasses.replace(AUTO, groups_apart_in_motion=False),
    ):
        whole = fly(units, sideways((0.0, 0.0, 800.0), 6.0, 40), settings)
        assert not any(plan.state.opened for plan in whole)
        assert all(plan.units.members[0] == (0, 1) for plan in whole)


def test_the_splat_sample_takes_every_kth_splat_of_each_cloud_each_standing_for_k():
    counts = [0, 5, 64, 127, 128, 1000]
    centres = RNG.normal(size=(sum(counts), 3))
    radii = RNG.uniform(1.0, 2.0, sum(counts))
    starts = np.concatenate([[0], np.cumsum(counts)])
    sample = SplatSample.of(centres, radii, starts)
    for cloud, count in enumerate(counts):
        rows = slice(sample.cloud_starts[cloud], sample.cloud_starts[cloud + 1])
        stride = max(1, count // SAMPLE_PER_CLOUD)
        expected = centres[starts[cloud] : starts[cloud + 1]][::stride]
        np.testing.assert_array_equal(sample.centres[rows], expected)
        np.testing.assert_array_equal(sample.radii[rows], radii[starts[cloud] : starts[cloud + 1]][::stride])
        assert np.sum(sample.weights[rows]) == pytest.approx(count, rel=1e-12)
    owners, got, _, weights = sample.of_clouds([5, 2], [7, 3])
    assert list(np.unique(owners)) == [3, 7] and np.sum(weights[owners == 7]) == pytest.approx(1000.0, rel=1e-12)
    np.testing.assert_array_equal(got[owners == 3], sample.centres[sample.cloud_starts[2] : sample.cloud_starts[3]])


def test_the_units_of_a_buffer_carry_its_sample_into_their_groups_clouds_and_rows():
    units = lod_units(CLOUDS)
    assert units.sample is not None and units.clouds.sample is units.sample
    assert units.and_clouds.take([0]).sample is units.sample
    assert np.sum(units.sample.weights) == pytest.approx(len(CLOUDS.radii), rel=1e-12)


def test_a_sprite_s_fragments_are_priced_at_what_they_cost_against_a_kernel_splat_s():
    """An atlas sprite's fragment fetches a texel (`SPRITE_FRAGMENT_COST` kernel fragments): a unit's fragments
    are weighted by its splats' areas, so a group of a sprite cloud and a splat cloud costs between the two, and
    the plan prices a sprite cloud's full 3D by as much more."""
    packed = Packed([blob((0, 0, 0)), blob((60, 0, 0), radius=24.0), blob((3000, 0, 0))], sprites=(1,))
    units = lod_units(packed)
    assert units.members == ((0, 1), (2,))
    sprite_share = 24.0**2 / (12.0**2 + 24.0**2)
    assert units.fragment_costs == pytest.approx([1.0 + sprite_share * (SPRITE_FRAGMENT_COST - 1.0), 1.0])
    assert units.clouds.fragment_costs == pytest.approx([1.0, SPRITE_FRAGMENT_COST])
    camera = Camera(position=(1500.0, 0.0, 4000.0), look_at=(1500.0, 0.0, 0.0), fov_y_deg=40.0)
    settings = RenderSettings(mode="auto", ring_radius=float("inf"), groups_apart_in_motion=False)
    costs = CostModel(particles=1e-9, fragments=1e-4)
    sprites = plan_frame(units, camera, (640, 480), settings, LodState(), 1, costs=costs)
    plain = plan_frame(
        dataclasses.replace(units, fragment_costs=np.ones(2)), camera, (640, 480), settings, LodState(), 1, costs=costs
    )
    assert sprites.clouds[0].full_ms / plain.clouds[0].full_ms == pytest.approx(units.fragment_costs[0], rel=1e-6)
    assert sprites.clouds[1].full_ms == pytest.approx(plain.clouds[1].full_ms, rel=1e-12)


def test_the_units_know_their_splats_lowest_and_highest_reach_and_carry_them_as_they_move():
    units = lod_units(CLOUDS)
    for row, members in enumerate(units.members):
        splats = np.concatenate([np.arange(CLOUDS.cloud_starts[c], CLOUDS.cloud_starts[c + 1]) for c in members])
        y, radii = CLOUDS.centres[splats, 1], CLOUDS.radii[splats]
        np.testing.assert_allclose(units.heights[row], [np.min(y - radii), np.max(y + radii)])
        assert units.heights[row, 1] - units.heights[row, 0] < 2.0 * units.radii[row]
    np.testing.assert_array_equal(units.and_clouds.take([3]).heights, units.clouds.heights[:1])
    # the wind carries each cloud: a unit's reach moves with its mean, and widens as its sphere grows
    shifts = np.array([[0.0, 10.0, 0.0], [0.0, 30.0, 0.0], [0.0, -5.0, 0.0], [0.0, 0.0, 0.0]])
    moved = units.moved(shifts, grown=2.0)
    np.testing.assert_allclose(moved.heights[0], units.heights[0] + 20.0 + np.array([-12.0, 12.0]))
    np.testing.assert_allclose(moved.heights[1], units.heights[1] - 5.0 + np.array([-2.0, 2.0]))
    assert LodUnits.of_spheres([[0.0, 0.0, 0.0]], [1.0]).heights is None
