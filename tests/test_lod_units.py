"""Units of the level of detail without GL: interpenetrating clouds grouped, and one impostor for a group."""

import dataclasses

import numpy as np

from cloudcore.lod.frameplan import LodState, plan_frame
from cloudcore.lod.units import LodUnits, interpenetrating_groups, lod_units
from cloudcore.scene import Camera, splats_bounding_sphere
from cloudcore.settings import RenderSettings

RNG = np.random.default_rng(11)


def blob(centre, count=300, spread=40.0, radius=12.0):
    points = RNG.normal(size=(count, 3)) * spread + np.asarray(centre, dtype=float)
    return points, np.full(count, radius)


class Packed:
    """The parts of a `ParticleBuffer` that `lod_units` reads."""

    def __init__(self, blobs):
        self.centres = np.concatenate([b[0] for b in blobs])
        self.radii = np.concatenate([b[1] for b in blobs])
        self.cloud_starts = np.concatenate([[0], np.cumsum([len(b[1]) for b in blobs])])
        spheres = [splats_bounding_sphere(*b) for b in blobs]
        self.bounding_centres = np.array([s[0] for s in spheres])
        self.bounding_radii = np.array([s[1] for s in spheres])
        self.finest_radii = np.array([b[1].min() for b in blobs])


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


def test_units_of_spheres_are_one_cloud_each():
    units = LodUnits.of_spheres(np.zeros((2, 3)), [1.0, 2.0])
    assert units.members == ((0,), (1,)) and len(units.radii) == 2
    assert dataclasses.is_dataclass(units)
