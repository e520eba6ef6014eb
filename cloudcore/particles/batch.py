"""A draw's particles: which of a `ParticleBuffer`'s particles one draw takes, sorted far to near from its eye.

`splat_batch` gathers the particles of some clouds (several together, since clouds interpenetrate in depth),
leaves out those the near fade, a formation, a depth range or the frustum make invisible, and sorts the rest
far to near (`SplatBatch`: their indices, 4 bytes a particle for the GPU).  A `SplatSelection` describes the
same choice for the GPU to make (`cloudcore.gl.splat_order`): how many it keeps is known there only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.lod.splat_coverage import splats_in_frustum
from cloudcore.maths.vectors import row_lengths
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.particles.depth_order import far_to_near


@dataclass(frozen=True)
class SplatBatch:
    """Particles of one draw, far to near from `eye`, as indices into `particles`."""

    particles: ParticleBuffer
    order: np.ndarray  # (n,) uint32
    eye: np.ndarray
    time_s: float | None
    #: whether its colours take the air between `eye` and each particle (`SplatPass.air`): the cloud pass's
    #: draws, not an impostor's, whose texture is seen from elsewhere
    through_air: bool = False

    def __len__(self) -> int:
        return len(self.order)

    @property
    def slots(self) -> int:
        """Instances its shading fills."""
        return len(self.order)

    def on_cpu(self) -> SplatBatch:
        """The batch (its particles are known on the CPU): as `SplatSelection.on_cpu`."""
        return self

    @property
    def centres(self) -> np.ndarray:
        """(n, 3) world centres, for the analytic overdraw estimate."""
        return self.particles.centres[self.order]

    @property
    def radii(self) -> np.ndarray:
        return self.particles.radii[self.order]


@dataclass(frozen=True, eq=False)
class SplatSelection:
    """The particles of one draw as `splat_batch` chooses them (its arguments), chosen and ordered by the GPU
    when `SplatPass` shades it: how many there are is known there only (`SplatPass.take_selected`).

    With `cells`, per cloud the draw its particles go to, from 0 up and non-decreasing: many draws from one
    eye, one into each cell of a layered target (`SplatPass.draw_cells`), chosen in one dispatch and
    sorted in one sort; shaded for one view a cell."""

    particles: ParticleBuffer
    clouds: tuple
    eye: np.ndarray
    depth_ranges: tuple | None
    time_s: float | None
    frustum: np.ndarray | None
    cells: tuple | None = None
    through_air: bool = False  # as `SplatBatch.through_air`

    def __post_init__(self):
        if self.cells is not None and (
            len(self.cells) != len(self.clouds)
            or (self.cells and self.cells[0] != 0)
            or np.any(np.diff(self.cells) < 0)
        ):
            raise ValueError(f"a selection's cells go from 0 up, one a cloud, got {self.cells} for {self.clouds}")

    @property
    def slots(self) -> int:
        """Instances its shading fills: one per particle of its clouds, chosen or not."""
        return int(self._counts.sum())

    @property
    def cell_count(self) -> int:
        return 1 if self.cells is None else (self.cells[-1] + 1 if self.cells else 0)

    def cell_slots(self) -> tuple[np.ndarray, np.ndarray]:
        """(each cell's first slot from the selection's first, the slots it holds): the particles of its clouds."""
        cells = np.zeros(len(self.clouds), dtype=np.int64) if self.cells is None else np.asarray(self.cells)
        held = np.bincount(cells, weights=self._counts, minlength=self.cell_count).astype(np.int64)
        return np.cumsum(held) - held, held

    @property
    def _counts(self) -> np.ndarray:
        starts = self.particles.cloud_starts
        clouds = np.asarray(self.clouds, dtype=np.int64)
        return (starts[clouds + 1] - starts[clouds]) if len(clouds) else np.zeros(0, dtype=np.int64)

    def on_cpu(self) -> SplatBatch:
        """The same particles chosen and sorted on the CPU, for what reads them there (overdraw's estimate)."""
        return splat_batch(
            self.particles, self.clouds, self.eye, self.depth_ranges, self.time_s, self.frustum, self.through_air
        )


def splat_batch(
    particles: ParticleBuffer,
    clouds,
    eye,
    depth_ranges=None,
    time_s: float | None = None,
    frustum: np.ndarray | None = None,
    through_air: bool = False,
) -> SplatBatch:
    """The visible particles of `clouds` (indices), sorted far to near from `eye`.

    `depth_ranges`, one (near, far) per cloud, keeps only the particles with
    near < distance from `eye` <= far: one layer of a cloud split around objects.
    `time_s`, the scene clock, fades forming and dissipating clouds (`ParticleBuffer.seen_from`), and
    the buffer's blend weights fade a cloud field's rings.
    `frustum`, the draw's planes (`cloudcore.world.camera.frustum_planes`), leaves out the splats outside it.
    `through_air`: `SplatBatch.through_air`.
    """
    starts = particles.cloud_starts
    # a cloud's particles are contiguous: slices gather them faster than an index array does
    pieces = [slice(starts[c], starts[c + 1]) for c in clouds]
    counts = [piece.stop - piece.start for piece in pieces]
    indices = np.concatenate([np.arange(piece.start, piece.stop) for piece in pieces]) if pieces else np.zeros(0, int)
    centres = np.concatenate([particles.centres[piece] for piece in pieces]) if pieces else np.zeros((0, 3))
    eye = np.asarray(eye, dtype=np.float64)
    offsets = centres - eye
    distances = row_lengths(offsets)
    kept = particles.drawn(indices, distances, time_s)
    if depth_ranges is not None:
        near = np.repeat([r[0] for r in depth_ranges], counts)
        far = np.repeat([r[1] for r in depth_ranges], counts)
        kept &= (distances > near) & (distances <= far)
    if frustum is not None:
        radii = np.concatenate([particles.radii[piece] for piece in pieces]) if pieces else np.zeros(0)
        kept &= splats_in_frustum(frustum, centres, radii)
    indices, distances = indices[kept], distances[kept]
    return SplatBatch(particles, indices[far_to_near(distances)].astype(np.uint32), eye, time_s, through_air)
