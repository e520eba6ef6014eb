"""The impostor atlas's layout: buddy cells never overlap, merge back when freed, grow and shrink by halves."""

import numpy as np
import pytest

from cloudcore.lod.atlas import AtlasLayout, Cell


def overlaps(a: Cell, b: Cell) -> bool:
    return (
        a.layer == b.layer and a.x < b.x + b.side and b.x < a.x + a.side and a.y < b.y + b.side and b.y < a.y + a.side
    )


def test_a_request_gets_the_smallest_power_of_two_cell_that_holds_it():
    layout = AtlasLayout(512, smallest=16)
    assert [layout.cell_side(side) for side in (1, 16, 17, 20, 64, 65, 360, 512)] == [16, 16, 32, 32, 64, 128, 512, 512]
    with pytest.raises(ValueError, match="1..512"):
        layout.cell_side(513)


def test_random_allocations_and_releases_never_overlap_and_free_everything_back():
    layout, rng, held = AtlasLayout(256, smallest=16), np.random.default_rng(7), []
    for step in range(3000):
        if held and rng.random() < 0.45:
            layout.release(held.pop(rng.integers(len(held))))
        else:
            side = int(rng.choice([8, 20, 28, 44, 64, 90, 128, 180, 256]))
            cell = layout.allocate(side)
            assert cell.side >= side and 0 <= cell.x and cell.x + cell.side <= 256 and cell.y + cell.side <= 256
            assert cell.layer < layout.layers and cell.x % cell.side == 0 and cell.y % cell.side == 0
            held.append(cell)
        if step % 50 == 0:
            assert not any(overlaps(a, b) for i, a in enumerate(held) for b in held[i + 1 :])
            assert all(cell.layer < layout.layers for cell in held)
            assert layout.texels_in_use == sum(cell.side**2 for cell in held)
    for cell in held:
        layout.release(cell)
    # every cell merged back into whole layers, and the layers halved down to one
    assert layout.layers == 1 and layout.texels_in_use == 0
    assert layout.allocate(256) == Cell(0, 0, 0, 256)


def test_cells_come_from_the_lowest_layer_with_room_and_layers_double_when_full():
    layout = AtlasLayout(64, smallest=16)
    whole = [layout.allocate(64) for _ in range(3)]
    assert [cell.layer for cell in whole] == [0, 1, 2] and layout.layers == 4
    layout.release(whole[1])
    assert layout.allocate(16).layer == 1  # the hole in layer 1 before the empty layer 3


def test_the_layers_halve_only_when_the_top_half_is_free_and_a_quarter_is_in_use():
    layout = AtlasLayout(64, smallest=16)
    cells = [layout.allocate(64) for _ in range(8)]
    assert layout.layers == 8
    for cell in cells[7:1:-1]:  # free the top six of eight: two layers in use, a quarter
        layout.release(cell)
    assert layout.layers == 4  # 8 -> 4; 4 -> 2 would leave half in use
    layout.release(cells[1])
    assert layout.layers == 2  # one of four in use: halved to two, not to one (half of two is in use)
    small = layout.allocate(16)  # layer 0 is full: it goes to layer 1
    layout.release(cells[0])
    assert small.layer == 1 and layout.layers == 2  # cells do not move: the one in the top layer keeps it


def test_bad_sides_are_refused():
    with pytest.raises(ValueError, match="powers of two"):
        AtlasLayout(500)
    with pytest.raises(ValueError, match="powers of two"):
        AtlasLayout(64, smallest=128)
