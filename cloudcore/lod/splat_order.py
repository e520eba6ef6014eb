"""Where full-3D draws and impostor regenerations choose and sort their particles, the CPU or the GPU, picked
by measurement.

`RenderSettings.splat_order` "auto" resolves here, per renderer.  On a
software rasterizer the GPU is the same cores, and its radix sort was
measured 30-40 times slower than numpy's, the frame 1.65 times
(docs/performance.md, "The GPU's order"): the CPU way, untried.  On a
GPU, the first frames that draw particles in full 3D or into impostors
alternate the two ways, `TRIAL_FRAMES` each, and the way whose impostor
updates and cloud passes together took less time (median) is kept.
Neighbouring frames of a moving camera draw nearly the same particles, so
the alternation compares like with like; a frame that sorts no particles
says nothing about either way and is not counted.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from types import MappingProxyType

WAYS = ("cpu", "gpu")
#: trial frames of each way before one is kept: a median of 4 is not moved by a single slow frame
TRIAL_FRAMES = 4
#: GL_RENDERER names of rasterizers that run on the CPU
SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "SwiftShader")


def software_rasterizer(renderer: str) -> bool:
    """Whether GL_RENDERER `renderer` names a rasterizer that runs on the CPU."""
    return any(name.lower() in renderer.lower() for name in SOFTWARE_RENDERERS)


@dataclass(frozen=True)
class SplatOrderChoice:
    """The measured trial of the two ways and the way kept (pure; the renderer holds one)."""

    #: way -> the cloud pass's ms of each of its trial frames
    trials: MappingProxyType = field(default_factory=lambda: MappingProxyType({way: () for way in WAYS}))
    kept: str | None = None

    def way(self, setting: str, renderer: str) -> str:
        """The way the next frame's full-3D draws take under `setting` ("auto", "cpu" or "gpu") on the GL
        named `renderer`."""
        if setting != "auto":
            return setting
        if self.kept is not None:
            return self.kept
        if software_rasterizer(renderer):
            return "cpu"
        # the way with fewer trials, the CPU's first: alternate frames
        return min(WAYS, key=lambda way: len(self.trials[way]))

    def observe(self, way: str, cloud_ms: float, full_particles: int) -> SplatOrderChoice:
        """The choice after a frame whose cloud pass took `cloud_ms` drawing `full_particles` in full 3D the
        way `way`; a kept way stays kept."""
        if self.kept is not None or full_particles <= 0 or not cloud_ms >= 0.0 or len(self.trials[way]) >= TRIAL_FRAMES:
            return self
        trials = {**self.trials, way: (*self.trials[way], float(cloud_ms))}
        kept = None
        if all(len(times) >= TRIAL_FRAMES for times in trials.values()):
            kept = min(WAYS, key=lambda way: statistics.median(trials[way]))
        return SplatOrderChoice(MappingProxyType(trials), kept)
