"""Wang's artist shading model (2004, section 5): colour levels x time of day, shading groups and the sun."""

import numpy as np
import pytest

from cloudcore.artist.artist_shading import (
    DEFAULT_GROUP_RADII,
    artist_colours,
    artist_uniforms,
    default_group_size,
    directional_factor,
    height_fractions,
    shading_groups,
    vertical_colour,
)
from cloudcore.artist.cloudgen import preset_cloud
from cloudcore.model.cloud_records import ArtistShading
from cloudcore.model.errors import FieldError
from cloudcore.world.sun import sun_direction

LEVELS = (
    (0.0, 0.2, 0.3, 0.4, 1.0),
    (0.25, 0.4, 0.4, 0.5, 0.9),
    (0.5, 0.6, 0.6, 0.6, 0.8),
    (0.75, 0.8, 0.7, 0.7, 0.7),
    (1.0, 1.0, 0.9, 0.8, 0.6),
)
MODEL = ArtistShading(
    levels=LEVELS,
    level_percent_by_hour=((1.0, 50.0), (12.0, 100.0), (23.0, 100.0)),
    directional_colour_by_hour=((6.0, 0.6, 0.3, 0.1), (12.0, 0.4, 0.4, 0.4)),
    directional_range=(0.1, 0.6, 0.9),
)
UP = np.array([0.0, 1.0, 0.0])


def test_vertical_colour_is_the_levels_at_their_heights_and_linear_between():
    at_noon = vertical_colour(MODEL, [0.0, 0.25, 0.5, 0.75, 1.0], 12.0)
    np.testing.assert_allclose(at_noon, np.array(LEVELS)[:, 1:], rtol=0, atol=1e-15)
    np.testing.assert_allclose(vertical_colour(MODEL, [0.125], 12.0)[0], [0.3, 0.35, 0.45, 0.95], atol=1e-15)
    # the end levels hold beyond the cloud
    np.testing.assert_array_equal(vertical_colour(MODEL, [-0.5, 1.5], 12.0), np.array(LEVELS)[[0, 4], 1:])


def test_the_hour_scales_the_colour_not_the_opacity():
    """Wang eq. 1: the level colour times the hour's percentage; the cloud gets darker at night, not thinner."""
    noon, early = vertical_colour(MODEL, [0.5], 12.0)[0], vertical_colour(MODEL, [0.5], 1.0)[0]
    np.testing.assert_allclose(early[:3], 0.5 * noon[:3], atol=1e-15)
    assert early[3] == noon[3] == 0.8


def test_time_of_day_tables_wrap_over_midnight():
    # keys at 23:00 (100%) and 01:00 (50%): midnight is halfway between them
    assert vertical_colour(MODEL, [1.0], 0.0)[0, 0] == pytest.approx(0.75 * 1.0)
    np.testing.assert_array_equal(vertical_colour(MODEL, [1.0], 0.0), vertical_colour(MODEL, [1.0], 24.0))
    single = ArtistShading(level_percent_by_hour=((9.0, 40.0),))  # one key: the same all day
    np.testing.assert_array_equal(vertical_colour(single, [0.3], 3.0), vertical_colour(single, [0.3], 17.0))
    with pytest.raises(ValueError, match="hour"):
        vertical_colour(MODEL, [0.5], 24.5)


def test_directional_mapping_is_biased_about_the_median():
    """Wang 5.2: [-1, 0] maps to [min, median], [0, 1] to [median, max]."""
    centre = np.array([100.0, 2000.0, -50.0])
    sun = np.array([0.0, 0.6, 0.8])
    side = np.array([1.0, 0.0, 0.0])  # perpendicular to the sun
    offsets = np.array([sun, -sun, side, 0.5 * sun + np.sqrt(0.75) * side, -0.5 * sun + np.sqrt(0.75) * side])
    factor = directional_factor(centre + 37.0 * offsets, np.tile(centre, (5, 1)), 3.0 * sun, MODEL)
    np.testing.assert_allclose(factor, [0.9, 0.1, 0.6, 0.6 + 0.5 * 0.3, 0.6 - 0.5 * 0.5], atol=1e-12)


def test_no_direction_gives_the_median():
    centre = np.array([[5.0, 5.0, 5.0]])
    assert directional_factor(centre, centre, UP, MODEL)[0] == 0.6  # a vertex at its group's centre
    assert directional_factor(centre + 1.0, centre, [0.0, 0.0, 0.0], MODEL)[0] == 0.6  # no sun vector
    huge = directional_factor([[1e300, 0.0, 0.0]], [[-1e300, 0.0, 0.0]], [1e-300, 0.0, 0.0], MODEL)
    assert huge[0] == pytest.approx(0.9)  # no overflow or underflow on the way


def test_artist_colours_are_ambient_plus_directional_clamped():
    rng = np.random.default_rng(3)
    vertices = rng.uniform([-500, 1000, -500], [500, 1600, 500], (200, 3))
    groups = vertices + rng.normal(size=(200, 3)) * 80.0
    sun = sun_direction(17.0)
    colours = artist_colours(MODEL, vertices, 1000.0, 1600.0, groups, sun, 17.0)
    ambient = vertical_colour(MODEL, (vertices[:, 1] - 1000.0) / 600.0, 17.0)
    directional = artist_uniforms(MODEL, 17.0, sun)["directional_colour"]
    factor = directional_factor(vertices, groups, sun, MODEL)
    expected = np.clip(ambient + np.column_stack([factor[:, None] * directional, np.zeros(200)]), 0.0, 1.0)
    np.testing.assert_allclose(colours, expected, atol=1e-15)
    assert colours.shape == (200, 4)
    lit, shaded = factor > 0.8, factor < 0.3
    assert lit.any() and shaded.any()
    assert colours[lit, 0].mean() > colours[shaded, 0].mean()  # the sunny side is brighter


def test_a_shader_fed_the_uniforms_reproduces_the_reference():
    """The GLSL's recipe (artist_uniforms' docstring), written out: the uniforms are all it needs."""
    rng = np.random.default_rng(8)
    vertices = rng.uniform([-300, 900, -300], [300, 1500, 300], (300, 3))
    groups = np.round(vertices / 200.0) * 200.0  # some vertices sit exactly on their group centre
    groups[:10] = vertices[:10]
    sun, hour, bottom, top = sun_direction(7.25), 7.25, 950.0, 1450.0
    u = artist_uniforms(MODEL, hour, sun)
    f = np.clip((vertices[:, 1] - bottom) / (top - bottom), 0.0, 1.0)
    upper = np.clip(np.searchsorted(u["level_heights"], f, side="right"), 1, 4)
    h0, h1 = u["level_heights"][upper - 1], u["level_heights"][upper]
    t = np.clip((f - h0) / (h1 - h0), 0.0, 1.0)[:, None]
    ambient = (1 - t) * u["level_colours"][upper - 1] + t * u["level_colours"][upper]
    v = vertices - groups
    length = np.linalg.norm(v, axis=1)
    d = np.where(length > 0, (v @ u["sun_direction"]) / np.where(length > 0, length, 1.0), 0.0)
    low, median, high = u["directional_range"]
    fraction = np.where(d < 0, median + d * (median - low), median + d * (high - median))
    shader = np.clip(ambient + np.column_stack([fraction[:, None] * u["directional_colour"], np.zeros(300)]), 0, 1)
    np.testing.assert_allclose(shader, artist_colours(MODEL, vertices, bottom, top, groups, sun, hour), atol=1e-12)


def test_artist_uniforms_are_plain_float_arrays():
    u = artist_uniforms(MODEL, 6.0, [0.0, 2.0, 0.0])
    shapes = {key: value.shape for key, value in u.items()}
    assert shapes == {
        "level_heights": (5,),
        "level_colours": (5, 4),
        "directional_colour": (3,),
        "directional_range": (3,),
        "sun_direction": (3,),
    }
    assert all(value.dtype == np.float64 for value in u.values())
    np.testing.assert_array_equal(u["sun_direction"], UP)
    np.testing.assert_allclose(u["directional_colour"], [0.6, 0.3, 0.1])
    np.testing.assert_allclose(u["level_colours"][:, :3], 0.5 * np.array(LEVELS)[:, 1:4] * (1 + 5 / 11), atol=1e-15)


@pytest.mark.parametrize("hour", [0.0, 3.0, 5.1, 12.0, 18.9, 23.99, 24.0])
def test_colours_stay_finite_and_in_range_for_any_hour_and_awkward_geometry(hour):
    """Sun below the horizon, a flat cloud, vertices on their group centres: finite, in [0, 1]."""
    vertices = np.array([[0.0, 1000.0, 0.0], [10.0, 1000.0, 0.0], [0.0, 1000.0, -1e-300]])
    groups = np.array([[0.0, 1000.0, 0.0]] * 3)
    for model in (MODEL, ArtistShading(), preset_cloud("cumulonimbus", "c", (0.0, 0.0, 0.0)).artist):
        colours = artist_colours(model, vertices, 1000.0, 1000.0, groups, sun_direction(hour), hour)
        assert np.all(np.isfinite(colours)) and colours.min() >= 0.0 and colours.max() <= 1.0
        # a flat cloud sits at the middle of its levels
        np.testing.assert_allclose(
            colours[0],
            np.clip(
                vertical_colour(model, [0.5], hour)[0]
                + np.append(artist_uniforms(model, hour, UP)["directional_colour"] * model.directional_range[1], 0.0),
                0.0,
                1.0,
            ),
        )


def test_night_leaves_the_ambient_percentage_and_no_sun():
    model = ArtistShading()
    night = artist_colours(model, [[0.0, 1000.0, 0.0]], 900.0, 1100.0, [[0.0, 900.0, 0.0]], sun_direction(1.0), 1.0)
    day = artist_colours(model, [[0.0, 1000.0, 0.0]], 900.0, 1100.0, [[0.0, 900.0, 0.0]], sun_direction(13.0), 13.0)
    assert night[0, :3].max() < 0.2 * day[0, :3].min()
    assert night[0, 3] == day[0, 3] == 1.0


def test_height_fractions():
    np.testing.assert_array_equal(
        height_fractions([900.0, 1000.0, 1100.0, 1300.0], 1000.0, 1200.0), [0.0, 0.0, 0.5, 1.0]
    )
    np.testing.assert_array_equal(height_fractions([5.0, 7.0], 6.0, 6.0), [0.5, 0.5])
    with pytest.raises(ValueError, match="bottom_y"):
        height_fractions([1.0], 2.0, 1.0)


def test_shading_groups_are_grid_cells_with_their_mean_as_centre():
    rng = np.random.default_rng(2)
    centres = rng.uniform(0.0, 1000.0, (500, 3))
    index, group_centres = shading_groups(centres, 250.0)
    assert index.shape == (500,) and index.dtype == np.int64 and group_centres.shape[1] == 3
    assert len(group_centres) == len(np.unique(index)) <= 64
    cells = np.floor((centres - centres.min(axis=0)) / 250.0)
    for group in range(len(group_centres)):
        members = index == group
        assert len(np.unique(cells[members], axis=0)) == 1  # one grid cell per group
        np.testing.assert_allclose(group_centres[group], centres[members].mean(axis=0), rtol=1e-12)
    assert len(np.unique(cells, axis=0)) == len(group_centres)  # and one group per occupied cell
    moved = shading_groups(centres + [12345.6, -700.0, 3.0], 250.0)
    np.testing.assert_array_equal(moved[0], index)  # moving a cloud never regroups it
    empty_index, empty_centres = shading_groups(np.zeros((0, 3)), 10.0)
    assert empty_index.shape == (0,) and empty_centres.shape == (0, 3)
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="group_size_m"):
            shading_groups(centres, bad)


def test_default_groups_hold_wangs_1_to_30_sprites():
    cloud = preset_cloud("cumulus_humilis", "h", (0.0, 1000.0, 0.0), seed=4)
    assert default_group_size(cloud.radii) == DEFAULT_GROUP_RADII * 75.0
    index, _ = shading_groups(cloud.centres, default_group_size(cloud.radii))
    sizes = np.bincount(index)
    assert sizes.max() <= 30 and np.median(sizes) >= 2


@pytest.mark.parametrize(
    "change, field",
    [
        (dict(levels=LEVELS[:4]), "levels"),
        (dict(levels=((0.5,) * 5,) * 5), "levels"),  # heights not increasing
        (dict(levels=((-0.1, 0, 0, 0, 1),) + LEVELS[1:]), "levels"),
        (dict(levels=((0.0, 1.5, 0, 0, 1),) + LEVELS[1:]), "levels"),
        (dict(levels=((0.0, 0, 0, np.nan, 1),) + LEVELS[1:]), "levels"),
        (dict(level_percent_by_hour=()), "level_percent_by_hour"),
        (dict(level_percent_by_hour=((24.0, 50.0),)), "level_percent_by_hour"),
        (dict(level_percent_by_hour=((5.0, 50.0), (5.0, 60.0))), "level_percent_by_hour"),
        (dict(level_percent_by_hour=((5.0, -1.0),)), "level_percent_by_hour"),
        (dict(directional_colour_by_hour=((5.0, 0.5, 0.5),)), "directional_colour_by_hour"),
        (dict(directional_colour_by_hour=((5.0, 0.5, 0.5, 2.0),)), "directional_colour_by_hour"),
        (dict(directional_range=(0.6, 0.5, 1.0)), "directional_range"),
        (dict(directional_range=(0.0, 0.5, 1.5)), "directional_range"),
        (dict(directional_range=(0.0, 0.5)), "directional_range"),
    ],
)
def test_bad_models_are_refused_naming_the_field(change, field):
    with pytest.raises(FieldError) as caught:
        ArtistShading(**change)
    assert caught.value.field == field
