"""The sprite atlas and each particle's sprite (Wang 2004, section 3.2)."""

import numpy as np
import pytest

from cloudcore.artist.sprite_art import render_atlas
from cloudcore.artist.sprites import (
    ATLAS_MAX_MIP_LEVEL,
    CELL_MARGIN_PIXELS,
    CELL_PIXELS,
    atlas_cell_uv,
    load_atlas,
    particle_sprites,
    sprite_choices,
)
from cloudcore.model.cloud_records import ATLAS_GRID, FLAT_BOTTOM, FOGGY, PUFFY, ROWS, WISPY, SpriteStyle
from cloudcore.model.errors import FieldError


def cells(atlas: np.ndarray) -> np.ndarray:
    """The atlas as (row, column, y, x, channel)."""
    side = atlas.shape[0] // ATLAS_GRID
    return atlas.reshape(ATLAS_GRID, side, ATLAS_GRID, side, -1).transpose(0, 2, 1, 3, 4)


def test_atlas_is_a_4x4_sheet_of_rgba_sprites():
    atlas = load_atlas()
    assert atlas.shape == (ATLAS_GRID * CELL_PIXELS, ATLAS_GRID * CELL_PIXELS, 4) and atlas.dtype == np.float32
    assert atlas.min() >= 0.0 and atlas.max() <= 1.0
    assert ROWS == ("flat_bottom", "foggy", "puffy", "wispy")
    coverage = cells(atlas)[..., 3].mean(axis=(2, 3))  # (row, column): mean opacity of each sprite
    assert np.all(coverage > 0.02), coverage
    assert np.all(coverage[FOGGY] < coverage[PUFFY])  # veils are thinner than puffs
    assert np.all(coverage[WISPY] < coverage[PUFFY])


def test_the_stored_atlas_is_what_the_script_draws():
    drawn = np.rint(render_atlas() * 255.0)
    stored = np.asarray(load_atlas(), dtype=np.float64) * 255.0
    assert np.abs(drawn - stored).max() <= 1.0  # one level of rounding where a platform's last bit differs


def test_sprites_fall_to_zero_before_the_cell_border_at_every_mip_level_used():
    """Bilinear filtering and mip levels 0..ATLAS_MAX_MIP_LEVEL never mix two sprites."""
    alpha = np.asarray(load_atlas()[..., 3], dtype=np.float64)
    margin = CELL_MARGIN_PIXELS
    for level in range(ATLAS_MAX_MIP_LEVEL + 1):
        per_cell = cells(alpha[..., None])[..., 0]  # (row, column, y, x)
        border = np.ones(per_cell.shape[2:], dtype=bool)
        border[margin:-margin, margin:-margin] = False
        assert np.all(per_cell[:, :, border] == 0.0), f"mip level {level}"
        assert margin >= 1
        side = alpha.shape[0] // 2
        alpha = alpha.reshape(side, 2, side, 2).mean(axis=(1, 3))  # the next mip level, a 2x2 box filter
        margin //= 2


def lowest_opaque_rows(sprite_alpha: np.ndarray) -> np.ndarray:
    """For each column of a cell, the image row of its lowest pixel with opacity above one half (-1: none)."""
    opaque = sprite_alpha > 0.5
    last = sprite_alpha.shape[0] - 1 - np.argmax(opaque[::-1], axis=0)
    return np.where(opaque.any(axis=0), last, -1)


def test_flat_bottom_sprites_have_a_flat_lower_edge_and_puffs_do_not():
    per_cell = cells(np.asarray(load_atlas()))
    for column in range(ATLAS_GRID):
        bottom = lowest_opaque_rows(per_cell[FLAT_BOTTOM, column, :, :, 3])
        edge = np.bincount(bottom[bottom >= 0]).argmax()
        flat = np.abs(bottom - edge) <= 1
        assert flat.sum() > 0.3 * CELL_PIXELS, column  # one straight edge along a third of the cell or more
        assert edge > CELL_PIXELS // 2  # in the lower half: the sprite sits on it
        puff = lowest_opaque_rows(per_cell[PUFFY, column, :, :, 3])
        assert np.max(np.bincount(puff[puff >= 0])) < 0.15 * CELL_PIXELS, column


def test_cell_coordinates_run_from_the_top_left():
    assert atlas_cell_uv(0) == (0.0, 0.0, 0.25, 0.25)
    assert atlas_cell_uv(7) == (0.75, 0.25, 1.0, 0.5)  # row 1 (foggy), column 3
    assert atlas_cell_uv(15) == (0.75, 0.75, 1.0, 1.0)
    atlas = load_atlas()
    u0, v0, u1, v1 = atlas_cell_uv(FLAT_BOTTOM * ATLAS_GRID + 2)
    side = atlas.shape[0]
    cell = atlas[int(v0 * side) : int(v1 * side), int(u0 * side) : int(u1 * side)]
    np.testing.assert_array_equal(cell, cells(atlas)[FLAT_BOTTOM, 2])
    for bad in (-1, 16, 2.0, True):
        with pytest.raises(ValueError, match="cell index"):
            atlas_cell_uv(bad)


STYLE = SpriteStyle(rows=(PUFFY, WISPY, WISPY), rotation_deg=(30.0, 120.0), seed=5)


def test_choices_come_from_the_style_rows_and_rotation_range():
    indices, rotations = sprite_choices(STYLE, 4000)
    assert indices.dtype == np.int32 and rotations.dtype == np.float64
    assert indices.shape == rotations.shape == (4000,)
    rows, columns = np.divmod(indices, ATLAS_GRID)
    assert set(rows.tolist()) == {PUFFY, WISPY}
    assert 0.28 < np.mean(rows == PUFFY) < 0.38  # listed once of three
    assert set(columns.tolist()) == set(range(ATLAS_GRID))
    assert np.all(rotations >= np.radians(30.0)) and np.all(rotations <= np.radians(120.0))
    assert np.ptp(rotations) > np.radians(85.0)


def test_choices_are_deterministic_and_adding_particles_keeps_the_others():
    small, large = sprite_choices(STYLE, 50), sprite_choices(STYLE, 500)
    np.testing.assert_array_equal(small[0], large[0][:50])
    np.testing.assert_array_equal(small[1], large[1][:50])
    again = sprite_choices(STYLE, 50)
    np.testing.assert_array_equal(small[0], again[0])
    other = sprite_choices(SpriteStyle(rows=STYLE.rows, rotation_deg=STYLE.rotation_deg, seed=6), 50)
    assert not np.array_equal(small[0], other[0])
    assert sprite_choices(STYLE, 0)[0].shape == (0,)


def test_the_base_of_the_cloud_draws_flat_bottoms_with_a_narrow_rotation():
    style = SpriteStyle(rows=(PUFFY,), flat_bottom_fraction=0.25, seed=1)
    heights = np.linspace(0.0, 1.0, 101)
    indices, rotations = sprite_choices(style, 101, heights)
    base = heights <= 0.25
    assert np.all(indices[base] // ATLAS_GRID == FLAT_BOTTOM)
    assert np.all(indices[~base] // ATLAS_GRID == PUFFY)
    assert np.all(np.abs(rotations[base]) <= np.radians(5.0))
    # the same as particle_sprites over centres spanning that height
    centres = np.column_stack([np.zeros(101), 1000.0 + 500.0 * heights, np.zeros(101)])
    np.testing.assert_array_equal(particle_sprites(style, centres)[0], indices)
    with pytest.raises(ValueError, match="height"):
        sprite_choices(style, 10)


@pytest.mark.parametrize(
    "change, field",
    [
        (dict(rows=()), "rows"),
        (dict(rows=(4,)), "rows"),
        (dict(rows=(True,)), "rows"),
        (dict(rotation_deg=(10.0, 0.0)), "rotation_deg"),
        (dict(rotation_deg=(0.0, 361.0)), "rotation_deg"),
        (dict(rotation_deg=(0.0, np.inf)), "rotation_deg"),
        (dict(flat_bottom_rotation_deg=(5.0, -5.0)), "flat_bottom_rotation_deg"),
        (dict(facing="up"), "facing"),
        (dict(seed=-1), "seed"),
        (dict(seed=2**31), "seed"),
        (dict(flat_bottom_fraction=1.5), "flat_bottom_fraction"),
    ],
)
def test_bad_styles_are_refused_naming_the_field(change, field):
    with pytest.raises(FieldError) as caught:
        SpriteStyle(**change)
    assert caught.value.field == field
