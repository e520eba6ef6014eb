"""Whether a batch of splats can be drawn as point sprites: one vertex per particle instead of four.

A Gaussian splat is a square of side 2r in the image plane.  Perspective
scales both image axes of a plane parallel to the image plane by the same
1/depth, so the square projects to a square: a point sprite of that side in
pixels, centred on the projected centre, covers the same pixels with the same
kernel coordinates (`gl_PointCoord`), and the picture does not change
(`tests/render/test_point_sprites.py`).  On llvmpipe a particle then costs less vertex
set-up (a quad's four vertices against a point's one), which is most of an
impostor regeneration's cost (docs/journal.md#point-sprites-third-session).

Three things keep a particle on quads:
- a look that varies across its square: an atlas sprite, a sprite facing
  the eye or lying flat, Wang's artist colours per corner (`plain_splats`);
- a square wider than the driver's largest point (255 px on llvmpipe), or
  narrower than its smallest (1 px: a smaller point is drawn 1 px wide);
- a centre outside the clip volume: GL discards such a point whole, where
  the quad would show the part inside.  `guard_band` widens the clip volume
  past the target's edges by a largest point (the viewport may exceed the
  framebuffer; what falls outside is not drawn), so every splat that fits
  in a point and touches the target has its centre inside.
A batch is drawn in its far-to-near order as alternate runs of points and
quads (`draw_runs`): next to the eye the large squares are the nearest, at
the end of the order, so a screen draw is mostly one run of each.
"""

from __future__ import annotations

import numpy as np

from cloudcore.artist.particle_styles import FACING_SPLAT, ParticleStyles

#: a run of points costs two more draws (one each side) than drawing it with its neighbours as quads: on
#: llvmpipe a draw costs what a few particles save, even at 6-7 particles; twice that for margin
#: (scripts/bench_point_sprites.py, docs/performance.md, "Full 3D: the splats, their order and their compositing")
SHORTEST_POINT_RUN = 16


def plain_splats(styles: ParticleStyles) -> np.ndarray:
    """(n,) bool: the particles that are plain Gaussian splats with one colour (Harris's shading)."""
    per_cloud = np.array([style.facing == FACING_SPLAT and style.artist is None for style in styles.clouds], dtype=bool)
    if not len(per_cloud):
        return np.zeros(len(styles.sprite_index), dtype=bool)
    return per_cloud[styles.cloud_index] & (styles.sprite_index < 0)


def guard_band(
    projection: np.ndarray, viewport: tuple[int, int, int, int], margin_px: float
) -> tuple[np.ndarray, tuple]:
    """(projection, (x, y, width, height) viewport) mapping the world to the same pixels as `projection`
    in the viewport (x, y, width, height), with the clip volume `margin_px` wider on every side."""
    x, y, width, height = map(int, viewport)
    margin = int(np.ceil(margin_px))
    wide, tall = width + 2 * margin, height + 2 * margin
    guarded = np.diag([width / wide, height / tall, 1.0, 1.0]) @ projection
    return guarded, (x - margin, y - margin, wide, tall)


def point_sprite_mask(
    centres_from_eye: np.ndarray,
    radii: np.ndarray,
    view_rotation: np.ndarray,
    projection: np.ndarray,
    viewport: tuple[int, int],
    point_sizes_px: tuple[float, float],
) -> np.ndarray:
    """(n,) bool: which splats at `centres_from_eye` (world offsets from the eye) can be drawn as points.

    `view_rotation` is the view matrix without its translation; `viewport` is (width, height) in
    pixels.  None can when the projection does not scale both axes alike in pixels (pixels not
    square, or shear); a splat can when its centre lies inside the clip volume and its square's side
    is within the driver's (smallest, largest) `point_sizes_px`.
    """
    count = len(radii)
    width, height = viewport
    focal_x, focal_y = projection[0, 0] * width, projection[1, 1] * height
    if projection[0, 1] != 0.0 or projection[1, 0] != 0.0 or not np.isclose(focal_x, focal_y, rtol=1e-6):
        return np.zeros(count, dtype=bool)
    # (4, n): a contiguous row a clip coordinate (numpy reduces rows of four slowly)
    centres = np.asarray(centres_from_eye, dtype=np.float64).reshape(count, 3)
    clip = (projection[:, :3] @ view_rotation[:3, :3]) @ centres.T + projection[:, 3:]
    w = clip[3]
    # a hair inside: the GPU clips in float32
    inside = (w > 0.0) & np.all(np.abs(clip[:3]) <= (1.0 - 1e-5) * w, axis=0)
    # the square's side in pixels: 2r * projection[1, 1] / w of the 2 that the viewport's height spans
    with np.errstate(divide="ignore", invalid="ignore"):
        sides = np.asarray(radii, dtype=np.float64) * focal_y / w
    smallest, largest = point_sizes_px
    return inside & (sides >= smallest) & (sides <= largest)


def draw_runs(mask: np.ndarray, shortest_point_run: int = SHORTEST_POINT_RUN) -> list[tuple[int, int, bool]]:
    """(start, stop, as points) of the draws of a batch whose particles `mask` allows as points.

    A batch is drawn in its far-to-near order, so a mixed batch is drawn as
    alternate runs of points and quads, one draw each; a run of points
    shorter than `shortest_point_run` is drawn with its neighbours as quads.
    """
    mask = np.array(mask, dtype=bool)
    for start, stop, value in _runs(mask):
        if value and stop - start < shortest_point_run:
            mask[start:stop] = False
    return _runs(mask)


def _runs(mask: np.ndarray) -> list[tuple[int, int, bool]]:
    """(start, stop, value) of each run of equal values in `mask`, in order."""
    if not len(mask):
        return []
    edges = np.flatnonzero(mask[1:] != mask[:-1]) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [len(mask)]])
    return [(int(a), int(b), bool(mask[a])) for a, b in zip(starts, stops)]
