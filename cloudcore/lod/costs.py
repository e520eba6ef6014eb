"""What a representation costs: a linear model of the cloud passes, its coefficients measured as the frames run.

The frame plan predicts the work of each unit's representation in machine-
independent quantities (`Work`: particles splatted, splat fragments blended
on the screen and into textures, impostor-quad pixels, regenerations, splat
draws) and prices it with a
`CostModel`, milliseconds per unit of work.  The coefficients are not
constants of the code: `CostEstimator` fits them to the passes' measured
times (what the renderer's impostor updates and cloud pass each add to the
frame: `cloudcore.gl.pass_clock`) by exponentially forgetting least squares, anchored to a prior.
On llvmpipe fragments dominate, so impostors win; on a GPU where a
regeneration's fixed cost dominates, full 3D does; the same plan code picks
each, from numbers measured on the machine it runs on.  The fragment counts
are estimates (a unit's splats as a ball of discs); screen and texture
fragments have coefficients of their own, so the fit also absorbs each
estimate's bias, which differs between the two (a near unit's off-screen
splats cost nothing on the screen; in its impostor texture, all of them
count).  Pure numpy: plan tests pass fixed models.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np

from cloudcore.maths.finite import nan_to_num
from cloudcore.runtime import disk_cache


@dataclass(frozen=True, slots=True)
class Work:
    """Counts of work, additive: one representation's, one pass's or a whole frame's."""

    particles: float = 0.0  # splats shaded, sorted and set up (screen or impostor texture)
    fragments: float = 0.0  # splat fragments blended on the screen (estimated: `splat_fragments`)
    texture_fragments: float = 0.0  # splat fragments blended into impostor textures (estimated likewise)
    quad_pixels: float = 0.0  # pixels of impostor quads, ring panels and crossfade layers drawn
    quads: float = 0.0  # those quads drawn, whatever their pixels: an instance of a run's draw, or a draw call
    regenerations: float = 0.0  # impostor textures (or ring segments) remade: target switch, clear, draw call
    batches: float = 0.0  # splat draws of the cloud pass: an upload of the order, a dispatch, a draw call
    #: screen pixels a cloud pass drawn at a reduced resolution is laid over (`cloudcore.gl.reduced_clouds`), once a
    #: composite: its upsampling, the tiles it covers, its blocks' nearest depth and the wait for the world's depth
    #: before it; a field of its own, as a quad's pixel it made the screen impostors' composites look dearer
    upsampled_pixels: float = 0.0

    # the planner adds and prices works tens of times a unit each frame, hundreds of units on a cloud field:
    # field by field by name, not numpy arrays of seven nor a loop over `fields` (3 of the 1.2M field's
    # 10 ms of planning a frame)
    def values(self) -> tuple[float, ...]:
        return (
            float(self.particles),
            float(self.fragments),
            float(self.texture_fragments),
            float(self.quad_pixels),
            float(self.quads),
            float(self.regenerations),
            float(self.batches),
            float(self.upsampled_pixels),
        )

    def __add__(self, other: Work) -> Work:
        return Work(
            self.particles + other.particles,
            self.fragments + other.fragments,
            self.texture_fragments + other.texture_fragments,
            self.quad_pixels + other.quad_pixels,
            self.quads + other.quads,
            self.regenerations + other.regenerations,
            self.batches + other.batches,
            self.upsampled_pixels + other.upsampled_pixels,
        )

    def scaled(self, factor: float) -> Work:
        return Work(*(factor * v for v in self.values()))

    def vector(self) -> np.ndarray:
        return np.array(self.values(), dtype=np.float64)


@dataclass(frozen=True)
class CostModel:
    """Milliseconds per unit of `Work`, field by field (the defaults: llvmpipe, `LLVMPIPE_COSTS`)."""

    particles: float = 8.5e-4
    fragments: float = 8.0e-6
    texture_fragments: float = 8.0e-6
    quad_pixels: float = 1.5e-5
    quads: float = 0.044
    regenerations: float = 0.5
    batches: float = 0.3
    upsampled_pixels: float = 6.7e-5

    def vector(self) -> np.ndarray:
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=np.float64)

    def ms(self, work: Work) -> float:  # a coefficient per field of Work, of the same name
        return math.fsum(
            (
                self.particles * work.particles,
                self.fragments * work.fragments,
                self.texture_fragments * work.texture_fragments,
                self.quad_pixels * work.quad_pixels,
                self.quads * work.quads,
                self.regenerations * work.regenerations,
                self.batches * work.batches,
                self.upsampled_pixels * work.upsampled_pixels,
            )
        )


#: a fragment of an atlas sprite (`cloudcore.artist.sprites`) costs this many of a Gaussian kernel splat's: its
#: texture fetch, before the sprite's transparent texels are discarded (`scripts/bench_sprite_fragments.py`;
#: docs/performance.md, "The cost model"); the plan
#: counts a unit's fragments so weighted (`LodUnits.fragment_costs`): one coefficient fitted to both priced neither
SPRITE_FRAGMENT_COST = 3.1


#: the prior: coefficients measured on llvmpipe, 2 cores (docs/performance.md, "The cost model"): a
#: particle's shading, vertices and sort 0.85 us; a splat fragment 8 ns on the screen or in a texture
#: (RGBA16F, blended); a regeneration's target switch, clear and draw 0.5 ms; a quad's draw call 44 us
#: beside its pixels (111 impostors drawn again at 160x120, 320x240 and 640x480: 4.9 ms of draws); a reduced cloud
#: pass 21 ms at 640x480 beside its draws, most of it llvmpipe's wait for the world's raster, the rest its composite
#: (docs/performance.md, "The cloud pass at a reduced resolution")
LLVMPIPE_COSTS = CostModel()


def inverse_square_depth(radius, distance):
    """E[1 / z^2] over a ball of `radius` whose centre is `distance` (> radius) from the eye, z the depth
    (scalars, or arrays element by element).

    A splat's area on screen (and in an impostor texture) goes as 1 / z^2, and a near cloud's near
    side looms: at 1.05 radii its splats cover 3.1 times what the centre's distance says.  With the
    ball's slices weighted by their area, 3 (d ln((d + R) / (d - R)) - 2R) / (2 R^3); far away the
    logarithm cancels to rounding, so the series 1 / d^2 (1 + 3/5 t^2 + 3/7 t^4 + 3/9 t^6), t = R / d.
    """
    radius, distance = np.asarray(radius, dtype=np.float64), np.asarray(distance, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d = np.where(distance > radius, distance, radius * (1.0 + 1e-6))
        t = radius / d
        t2 = t * t
        result = (1.0 + t2 * (0.6 + t2 * (3.0 / 7.0 + t2 / 3.0))) / (d * d)
        # the logarithm only where the series falls short: the near few of a scene's thousands of units
        near = np.flatnonzero(np.reshape(t >= 0.2, -1))
        if len(near):
            result = np.reshape(result, -1)
            r, dn = np.broadcast_to(radius, d.shape).reshape(-1)[near], np.reshape(d, -1)[near]
            result[near] = 3.0 * (dn * np.log1p(2.0 * r / (dn - r)) - 2.0 * r) / (2.0 * r**3)
            result = result.reshape(d.shape)
        result = np.where(radius > 0.0, result, 1.0 / np.maximum(distance * distance, 1e-18))
    return float(result) if result.ndim == 0 else result


def splat_fragments(radius_squares, radius, distance, focal_px: float, particles, screen_pixels: float):
    """Fragments of a unit's splats seen from `distance`: their disc areas pi (f r / z)^2 summed, z spread
    over the unit's bounding ball (`inverse_square_depth`); each disc at most the screen (scalars, or
    arrays of units)."""
    with np.errstate(over="ignore"):  # a disc past any float is capped to the screen all the same
        area = math.pi * np.square(focal_px) * np.asarray(radius_squares) * inverse_square_depth(radius, distance)
    result = np.minimum(area, np.asarray(particles) * screen_pixels)
    return float(result) if np.ndim(result) == 0 else result


def regeneration_fragments(particles, radius_squares, radius, distance, quad_half_side, texture_size):
    """Remaking units' impostors: the fragments of their particles splatted into textures whose side spans
    the quad (`quad_half_side` at the centre's `distance`); arrays of units (or scalars)."""
    size = np.asarray(texture_size, dtype=np.float64)
    focal_texels = size * distance / (2.0 * np.maximum(quad_half_side, np.finfo(float).tiny))
    return splat_fragments(radius_squares, radius, distance, focal_texels, particles, size * size)


#: how much the fitted coefficients remember of each frame: 0.97 is about the last 30 frames
FORGETTING = 0.97
#: weight of the prior, in squared milliseconds of evidence: a term worth 10 ms a frame outweighs it within
#: a frame, so a machine unlike the prior's (a GPU) moves the fit in a few frames, while the small terms
#: (a regeneration's fixed cost) and the split between terms that grow together (particles and their
#: fragments) stay near the prior through the noise of frame times
PRIOR_WEIGHT = 100.0
#: the fitted coefficients stay within this factor of the prior either way (a pass timed during a
#: stall, or work the model does not see, must not make a representation look free or prohibitive)
RATIO_LIMIT = 30.0


@dataclass(frozen=True, eq=False)
class CostEstimator:
    """Fits a `CostModel` to measured pass times: y_ms = model . work, least squares with forgetting.

    Solved in units of the prior (v_i = coefficient_i / prior_i, so every unknown is near 1) with
    a ridge term pulling v toward 1; immutable: `observe` returns the next estimator.
    """

    prior: CostModel = LLVMPIPE_COSTS
    normal: np.ndarray = None  # sum of forgotten g g^T, g = work * prior (the prior's ms per field)
    right: np.ndarray = None  # sum of forgotten g y
    frames: int = 0

    def __post_init__(self):
        size = len(fields(CostModel))
        if self.normal is None:
            object.__setattr__(self, "normal", np.zeros((size, size)))
        if self.right is None:
            object.__setattr__(self, "right", np.zeros(size))

    def observe(self, measurements) -> CostEstimator:
        """Add this frame's (work, measured ms) pairs, one per timed pass."""
        normal, right = FORGETTING * self.normal, FORGETTING * self.right
        prior = self.prior.vector()
        for work, ms in measurements:
            if not (math.isfinite(ms) and ms >= 0.0):
                continue
            g = work.vector() * prior
            normal = normal + np.outer(g, g)
            right = right + g * ms
        return CostEstimator(self.prior, normal, right, self.frames + 1)

    def model(self) -> CostModel:
        """The coefficients the measurements so far support (the prior before any)."""
        return self._fitted

    @cached_property  # the estimator is immutable: a frame that fits no costs (full 3D) keeps the last one's
    def _fitted(self) -> CostModel:
        size = len(self.right)
        ratios = np.linalg.solve(self.normal + PRIOR_WEIGHT * np.eye(size), self.right + PRIOR_WEIGHT)
        ratios = np.clip(nan_to_num(ratios, nan=1.0), 1.0 / RATIO_LIMIT, RATIO_LIMIT)
        return CostModel(*(ratios * self.prior.vector()))


#: fitted frames a model needs before it is remembered for the next run on the machine (`remember_fit`)
FRAMES_TO_REMEMBER = 60
_REMEMBERED = "cost-model"
#: set to "off" to start every run from the prior and remember nothing (the test suite does: its runs must
#: not depend on the ones before)
MEMORY_VARIABLE = "CLOUDVIEW_COST_MEMORY"


def _memory_on() -> bool:
    return os.environ.get(MEMORY_VARIABLE, "on") != "off"


def remembered_prior(machine: dict) -> CostModel | None:
    """The model the last run on `machine` (its GL, processor and cores: `FrameRenderer`'s key) fitted, to
    start this run's fit from instead of the llvmpipe prior; None if none was remembered, or a stored one is
    unusable (every coefficient must be finite and > 0)."""
    held = disk_cache.load(_REMEMBERED, machine) if _memory_on() else None
    if held is None:
        return None
    coefficients = np.asarray(held.get("coefficients", ()), dtype=np.float64)
    if coefficients.shape != (len(fields(CostModel)),) or not np.all(np.isfinite(coefficients) & (coefficients > 0)):
        return None
    return CostModel(*(float(c) for c in coefficients))


def remember_fit(machine: dict, estimator: CostEstimator) -> bool:
    """Keep `estimator`'s model for the next run on `machine` when it has fitted `FRAMES_TO_REMEMBER` frames;
    whether it was kept (a cache that cannot be written keeps nothing, and says so)."""
    if estimator.frames < FRAMES_TO_REMEMBER or not _memory_on():
        return False
    try:
        disk_cache.store(_REMEMBERED, machine, {"coefficients": estimator.model().vector()})
    except OSError:
        return False
    return True
