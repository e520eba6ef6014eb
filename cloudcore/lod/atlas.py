"""Where impostors live in one array texture: square power-of-two cells in layers, by quadtree buddy allocation.

llvmpipe pays for every texture a draw binds (a run of impostor quads each from
its own texture cost more per quad than the same run from regions of one
texture: docs/journal.md#the-level-of-detail-by-error-and-cost), so the impostors of the units share
one array texture and a run of them is one instanced draw.  A request of side
s gets a cell of the smallest power of two >= s (at least `smallest`): a
layer of side `layer_side` splits into four quadrants, those into four, and
so on; a freed cell merges back with its three siblings when they are all
free.  Cells are taken from the lowest layer that has room, so the top layers
empty first: the layout doubles its layers when none has room and halves them
when the top half has been empty and at most a quarter is in use, so a texture
holding it neither thrashes nor keeps what a busy moment once needed.

Pure: the GL side (`cloudcore.gl.impostor_atlas`) renders into the cells and
resizes its texture to `layers`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Cell:
    """A square of the atlas: texels [x, x + side) x [y, y + side) of layer `layer`."""

    layer: int
    y: int
    x: int
    side: int


class AtlasLayout:
    def __init__(self, layer_side: int, smallest: int = 16):
        if not (_power_of_two(layer_side) and _power_of_two(smallest) and smallest <= layer_side):
            raise ValueError(f"atlas sides must be powers of two, smallest <= layer side: {smallest}, {layer_side}")
        self.layer_side, self.smallest = layer_side, smallest
        self.layers = 0
        self._free: dict[int, set[Cell]] = {}  # side -> free cells of that side
        self._used: set[Cell] = set()
        self.texels_in_use = 0

    def cell_side(self, side: int) -> int:
        """The side of the cell a request of `side` texels gets."""
        if not 0 < side <= self.layer_side:
            raise ValueError(f"an atlas cell holds sides 1..{self.layer_side}, not {side}")
        return power_of_two_at_least(side, self.smallest)

    def allocate(self, side: int) -> Cell:
        """A free cell for a square of `side` texels, growing the layers when none has room."""
        wanted = self.cell_side(side)
        sides = [s for s, cells in self._free.items() if s >= wanted and cells]
        if not sides:
            self._grow()
            return self.allocate(side)
        # the lowest layer with room first, then the smallest block there: the top layers stay free to be trimmed
        cell = min((c for s in sides for c in self._free[s]), key=lambda c: (c.layer, c.side, c.y, c.x))
        self._free[cell.side].remove(cell)
        while cell.side > wanted:
            half = cell.side // 2
            quadrants = [Cell(cell.layer, cell.y + dy, cell.x + dx, half) for dy in (0, half) for dx in (0, half)]
            self._free.setdefault(half, set()).update(quadrants[1:])
            cell = quadrants[0]
        self._used.add(cell)
        self.texels_in_use += cell.side**2
        return cell

    def release(self, cell: Cell) -> None:
        """Give `cell` back, merging it with its siblings while all four are free; may halve the layers."""
        self._used.remove(cell)
        self.texels_in_use -= cell.side**2
        while cell.side < self.layer_side:
            parent_side = cell.side * 2
            parent = Cell(cell.layer, cell.y - cell.y % parent_side, cell.x - cell.x % parent_side, parent_side)
            siblings = [
                Cell(cell.layer, parent.y + dy, parent.x + dx, cell.side)
                for dy in (0, cell.side)
                for dx in (0, cell.side)
            ]
            free = self._free.setdefault(cell.side, set())
            if not all(s == cell or s in free for s in siblings):
                break
            free.difference_update(siblings)
            cell = parent
        self._free.setdefault(cell.side, set()).add(cell)
        self._trim()

    def _grow(self) -> None:
        added = range(self.layers, max(1, 2 * self.layers))
        self._free.setdefault(self.layer_side, set()).update(Cell(layer, 0, 0, self.layer_side) for layer in added)
        self.layers = len(added) + self.layers

    def _trim(self) -> None:
        """Halve the layers while the top half is wholly free and at most a quarter of the texels are in use."""
        whole = self._free.get(self.layer_side, set())
        while self.layers > 1:
            top = [Cell(layer, 0, 0, self.layer_side) for layer in range(self.layers // 2, self.layers)]
            if not all(cell in whole for cell in top) or 4 * self.texels_in_use > self.layers * self.layer_side**2:
                return
            whole.difference_update(top)
            self.layers //= 2


def power_of_two_at_least(side: int, smallest: int = 1) -> int:
    """The smallest power of two >= `side` and >= `smallest`."""
    return max(smallest, 1 << (int(side) - 1).bit_length())


def _power_of_two(value: int) -> bool:
    return value > 0 and value & (value - 1) == 0
