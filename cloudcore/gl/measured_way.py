"""Two ways of doing the same work, picked by measurement: where splats are sorted (`splat_order`) and what
composites full 3D's splats (`compositing`).

A setting's "auto" resolves here, per renderer.  On a software rasterizer the
GPU is the same cores: there the first way is taken untried (the CPU's sort:
the radix sort on llvmpipe is several times slower than numpy's; the raster:
the compute compositor takes longer there; docs/performance.md, "The GPU's
order" and "Compositing by compute").  On a GPU, the first frames that do the work alternate
the two ways, `TRIAL_FRAMES` each, and the way whose passes took less time
(median) is kept.  Neighbouring frames of a moving camera draw nearly the
same particles, so the alternation compares like with like; a frame that does
none of the work says nothing about either way and is not counted.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass

from cloudcore.model.settings import SPLAT_ORDER_WAYS

#: trial frames of each way before one is kept: a median of 4 is not moved by a single slow frame
TRIAL_FRAMES = 4
#: GL_RENDERER names of rasterizers that run on the CPU
SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "SwiftShader")


def software_rasterizer(renderer: str) -> bool:
    """Whether GL_RENDERER `renderer` names a rasterizer that runs on the CPU."""
    return any(name.lower() in renderer.lower() for name in SOFTWARE_RENDERERS)


@dataclass(frozen=True)
class MeasuredWay:
    """The measured trial of two `ways` and the way kept (pure; the renderer holds one a choice); the first way
    is the one a software rasterizer takes untried."""

    ways: tuple[str, str] = SPLAT_ORDER_WAYS
    #: per way, in the order of `ways`, the milliseconds of its trial frames
    trials: tuple[tuple[float, ...], ...] = ((), ())
    kept: str | None = None

    def times(self, way: str) -> tuple[float, ...]:
        """The milliseconds of `way`'s trial frames so far."""
        return self.trials[self.ways.index(way)]

    def way(self, setting: str, renderer: str) -> str:
        """The way the next frame takes under `setting` ("auto" or one of `ways`) on the GL named `renderer`."""
        if setting != "auto":
            return setting
        if self.kept is not None:
            return self.kept
        if software_rasterizer(renderer):
            return self.ways[0]
        # the way with fewer trials, the first's first: alternate frames
        return min(self.ways, key=lambda way: len(self.times(way)))

    def observe(self, way: str, ms: float, work: int) -> MeasuredWay:
        """The choice after a frame whose passes took `ms` doing `work` (particles; 0: none of the work this
        choice is about) the way `way`; a kept way stays kept."""
        if self.kept is not None or work <= 0 or not ms >= 0.0 or len(self.times(way)) >= TRIAL_FRAMES:
            return self
        trials = tuple((*times, float(ms)) if name == way else times for name, times in zip(self.ways, self.trials))
        kept = None
        if all(len(times) >= TRIAL_FRAMES for times in trials):
            kept = min(self.ways, key=lambda name: statistics.median(trials[self.ways.index(name)]))
        return MeasuredWay(self.ways, trials, kept)
