"""A cloud field's clouds shadowing one another (`cloudcore.light.cell_shadows`, `cloudcore.field.shadow_cells`):
a cell behind another toward the sun gets less of it, a cloud made twice in a ring's blend band does not shadow its
twin, a cell casts by its blend weight (none as it enters), and the light kept between sets of cells is the light
made at once."""

import numpy as np
import pytest

from cloudcore.field.shadow_cells import CellShadowing, casting_weights, cell_shadowing
from cloudcore.field.state import FADE_KEY_STEPS, FieldState, update_field
from cloudcore.light.cell_shadows import SunThroughCells, sun_through_other_cells
from cloudcore.light.illumination import IlluminationCache, beam_of, illuminate_clouds
from cloudcore.model.scene import CloudField, Light, Shading
from cloudcore.world.sun import sun_direction
from tests.conftest import ball

SUN = sun_direction(15.5)
FIELD = CloudField(seed=2014, coverage=0.4, cell_size=500.0, rings=4, layers=4, altitude=(1200.0, 2400.0))
EYE = np.array([-12000.0, 2000.0, 3000.0])


def cells_of(clouds, corners, side=500.0) -> CellShadowing:
    """Each of `clouds` in its own cell of `side` at `corners` (x, z), every particle casting all its opacity."""
    count = sum(len(c.particles) for c in clouds)
    return CellShadowing(np.asarray(corners, float), np.full(len(clouds), side), np.ones(count))


def through(clouds, shadowing, sun=SUN) -> list[np.ndarray]:
    centres, radii, opacity, starts = beam_of(clouds, Shading())
    return np.split(sun_through_other_cells(centres, radii, opacity, starts, shadowing, sun), starts[1:-1])


def test_a_field_cloud_behind_another_toward_the_sun_receives_less_light():
    front_centre = np.array([250.0, 1800.0, 250.0])
    front = ball(front_centre, 200.0, 400, seed=1)
    behind = ball(front_centre - 900.0 * np.asarray(SUN), 200.0, 400, seed=2)  # along the light, in another cell
    aside = ball(front_centre + [0.0, 0.0, 2000.0], 200.0, 400, seed=3)
    corners = [[0.0, 0.0], np.floor(behind.centres.mean(axis=0)[[0, 2]] / 500.0) * 500.0, [0.0, 2000.0]]
    assert not np.array_equal(corners[0], corners[1])
    shares = through([front, behind, aside], cells_of([front, behind, aside], corners))
    assert shares[0].tolist() == [1.0] * len(shares[0])  # nothing between it and the sun
    assert shares[2].tolist() == [1.0] * len(shares[2])
    assert shares[1].mean() < 0.6 and shares[1].max() <= 1.0 and shares[1].min() > 0.0
    # alone, a cloud's own particles never shadow it: Harris's light pass has them
    (alone,) = through([behind], cells_of([behind], corners[1:2]))
    assert alone.tolist() == [1.0] * len(alone)


def test_a_particle_whose_place_lies_in_the_receiver_s_cell_does_not_shadow_it():
    """The blend bands' twin: a coarser cell's particles over a finer cell's footprint are the same cloud."""
    front_centre = np.array([250.0, 1800.0, 250.0])
    front = ball(front_centre, 200.0, 400, seed=1)
    behind = ball(front_centre - 300.0 * np.asarray(SUN), 200.0, 400, seed=2)
    # `behind`'s cell, 2 km across, holds `front`'s place too: `front` stands for part of the same cloud
    shares = through([front, behind], cells_of([front, behind], [[0.0, 0.0], [-1000.0, -1000.0]], 2000.0))
    assert shares[1].tolist() == [1.0] * len(shares[1])
    # ... and in cells apart, the one shadows the other
    apart = cells_of([front, behind], [[0.0, 0.0], [5000.0, 5000.0]])
    assert through([front, behind], apart)[1].mean() < 0.8


@pytest.fixture(scope="module")
def demo_field() -> tuple:
    frame, state = update_field(FIELD, EYE)
    casting = casting_weights(frame.mean_weights, frame.cloud_starts)
    return frame, state, cell_shadowing(0, (state,), (len(frame.clouds),), 0, casting)


def test_a_particle_casts_its_blend_weight_and_twins_in_a_blend_band_take_none_of_each_other(demo_field):
    frame, state, shadowing = demo_field
    steps = np.round(frame.mean_weights * FADE_KEY_STEPS) / FADE_KEY_STEPS  # each cloud's mean weight's step
    assert np.array_equal(shadowing.casting, np.repeat(steps, np.diff(frame.cloud_starts)))
    assert 0.0 < shadowing.casting.mean() < 1.0  # the rings' bands blend
    assert shadowing.casting.min() == 0.0 and shadowing.casting.max() == 1.0
    # a level-1 cloud whose four finer cells are made, and one of them that is a cloud: the same sky twice; neither
    # takes a shadow from the other's particles over its own footprint
    made = set(state.cells)
    slots = {key: index for index, key in enumerate(state.slots) if key is not None}
    parent = next(
        key
        for key in slots
        if key[0] == 1
        and all((0, 2 * key[1] + a, 2 * key[2] + b) in made for a in (0, 1) for b in (0, 1))
        and any((0, 2 * key[1] + a, 2 * key[2] + b) in slots for a in (0, 1) for b in (0, 1))
    )
    child = next(
        (0, 2 * parent[1] + a, 2 * parent[2] + b)
        for a in (0, 1)
        for b in (0, 1)
        if (0, 2 * parent[1] + a, 2 * parent[2] + b) in slots
    )
    pair = [slots[child], slots[parent]]
    particles = np.concatenate([np.arange(frame.cloud_starts[i], frame.cloud_starts[i + 1]) for i in pair])
    corner, side = shadowing.corners[pair[0]], shadowing.sides[pair[0]]
    place = frame.clouds[pair[1]].centres[:, [0, 2]]
    over_child = np.all((place >= corner) & (place < corner + side), axis=1)
    casting = shadowing.casting[particles].copy()
    casting[len(frame.clouds[pair[0]].particles) :][~over_child] = 0.0  # the parent's particles over the child alone
    twins = CellShadowing(shadowing.corners[pair], shadowing.sides[pair], casting)
    for share in through([frame.clouds[i] for i in pair], twins):
        assert share.tolist() == [1.0] * len(share)


def test_a_cells_shadow_follows_its_blend_weight_and_enters_at_weight_0_with_none():
    """A cell's casting is its weight: the light behind it at weight w lies between none and all of its shadow,
    falling as w grows, and at weight 0 (a cell entering or leaving) it is the light without the cell, so that
    nothing steps as it comes."""
    front_centre = np.array([250.0, 1800.0, 250.0])
    front = ball(front_centre, 200.0, 400, seed=1)
    behind = ball(front_centre - 900.0 * np.asarray(SUN), 200.0, 400, seed=2)
    corners = [[0.0, 0.0], np.floor(behind.centres.mean(axis=0)[[0, 2]] / 500.0) * 500.0]
    cells = cells_of([front, behind], corners)
    means = []
    for weight in np.linspace(0.0, 1.0, 5):
        casting = np.concatenate([np.full(len(front.particles), weight), np.ones(len(behind.particles))])
        shadowing = CellShadowing(cells.corners, cells.sides, casting)
        means.append(through([front, behind], shadowing)[1].mean())
    assert means[0] == 1.0  # entering at weight 0: no shadow at all
    assert np.all(np.diff(means) < 0.0)  # darker with every step
    # each particle adds -ln(1 - w b K): at half weight the light lies strictly between none of the shadow and all
    half, full = means[2], means[-1]
    assert full < half < 1.0
    # a cloud under half a step casts nothing
    weights = [0.0, 0.4 / FADE_KEY_STEPS, 0.6 / FADE_KEY_STEPS, 1.0]
    assert casting_weights(weights, [0, 1, 3, 4, 6]).tolist() == [0.0, 0.0, 0.0, 0.25, 1.0, 1.0]


def test_a_change_of_a_cells_casting_remakes_the_clouds_it_reaches_alone():
    """Held between frames: a change of casting (the weights of a frame whose cells changed) makes again the clouds
    behind the particles whose casting changed, and the result is the one made at once."""
    front_centre = np.array([250.0, 1800.0, 250.0])
    front = ball(front_centre, 200.0, 400, seed=1)
    behind = ball(front_centre - 900.0 * np.asarray(SUN), 200.0, 400, seed=2)
    aside = ball(front_centre + [0.0, 0.0, 3000.0], 200.0, 400, seed=3)
    clouds = [front, behind, aside]
    cells = cells_of(clouds, [[0.0, 0.0], np.floor(behind.centres.mean(axis=0)[[0, 2]] / 500.0) * 500.0, [0.0, 3000.0]])
    beam = beam_of(clouds, Shading())
    cache = SunThroughCells()
    for weight in (0.25, 0.5):
        casting = cells.casting.copy()
        casting[: len(front.particles)] = weight
        shadowing = CellShadowing(cells.corners, cells.sides, casting)
        held = cache.through(clouds, *beam, shadowing, SUN)
        assert np.allclose(np.concatenate(held), sun_through_other_cells(*beam, shadowing, SUN), rtol=0.0, atol=1e-12)
    assert cache.clouds_made == 1  # the cloud behind the front one alone


def test_the_shares_kept_between_sets_of_cells_are_those_made_at_once_and_only_the_reached_clouds_are_made():
    cache, state, shading = SunThroughCells(), FieldState(), Shading()
    before: dict = {}
    for step in range(5):
        frame, state = update_field(FIELD, EYE + [step * 400.0, 0.0, 0.0], state)
        casting = casting_weights(frame.mean_weights, frame.cloud_starts)
        shadowing = cell_shadowing(0, (state,), (len(frame.clouds),), 0, casting)
        beam = beam_of(frame.clouds, shading)
        held = cache.through(frame.clouds, *beam, shadowing, SUN)
        at_once = sun_through_other_cells(*beam, shadowing, SUN)
        assert np.allclose(np.concatenate(held), at_once, rtol=0.0, atol=1e-12)
        if step:
            assert cache.clouds_made < len(frame.clouds)
            kept = [share is before.get(id(cloud)) for cloud, share in zip(frame.clouds, held)]
            assert sum(kept) == len(frame.clouds) - cache.clouds_made
        before = dict(zip(map(id, frame.clouds), held))
    assert (at_once < 0.5).any() and (at_once == 1.0).any()
    # another sun makes every cloud again
    cache.through(frame.clouds, *beam, shadowing, sun_direction(12.0))
    assert cache.clouds_made == len(frame.clouds)


def test_the_light_pass_dims_a_field_s_sun_alone_and_the_cache_holds_it_per_shadowing(demo_field):
    frame, _, shadowing = demo_field
    clouds = list(frame.clouds)
    lights = (Light(tuple(SUN), (1.0, 0.9, 0.8), 1.0), Light((0.0, 1.0, 0.0), (0.5, 0.6, 1.0), 0.3))
    alone = np.concatenate(illuminate_clouds(clouds, Shading(), lights, "raster"))
    cache = IlluminationCache()
    shadowed = np.concatenate(cache.incident(clouds, Shading(), lights, "raster", between_clouds=shadowing))
    assert np.array_equal(shadowed[:, 1], alone[:, 1])  # the skylight is not the sun
    assert np.all(shadowed[:, 0] <= alone[:, 0]) and shadowed[:, 0].mean() < 0.9 * alone[:, 0].mean()
    direct = np.concatenate(illuminate_clouds(clouds, Shading(), lights, "raster", between_clouds=shadowing))
    assert np.array_equal(direct, shadowed)
    cache.incident(clouds, Shading(), lights, "raster", between_clouds=shadowing)
    assert cache.between_made == 1
    # the same clouds shadowing otherwise (a clear cell came) are made again
    again = CellShadowing(shadowing.corners, shadowing.sides, shadowing.casting.copy())
    cache.incident(clouds, Shading(), lights, "raster", between_clouds=again)
    assert cache.between_made == 2
