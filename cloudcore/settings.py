"""How clouds are drawn: one settings object for the GUI, the command line and the benchmarks.

`mode` picks the representation: "full" draws every particle every frame (the
reference picture), "impostor" draws every cloud from a cached texture, "auto"
chooses per cloud by distance (full near, crossfade, impostor far, the ring
beyond `ring_radius`).  Distances for the fade are in units of the cloud's
bounding radius, as in the gamedev.net article (full below 2r, impostor above 4r).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MODES = ("auto", "full", "impostor")


@dataclass(frozen=True)
class RenderSettings:
    mode: str = "auto"
    #: degrees: an impostor is regenerated once the eye has turned this far around its cloud's centre
    tolerance_deg: float = 0.15
    #: metres: clouds wholly beyond this horizontal distance join Wang's ring of 8 impostors; inf: no ring
    ring_radius: float = 4000.0
    #: impostor texture sides, powers of two
    impostor_min_size: int = 16
    impostor_max_size: int = 512
    #: texels across the radius of a cloud's finest particle that an impostor texture must give; a finer
    #: texture only resamples smooth Gaussians, so none is made (0: the screen's resolution alone decides)
    impostor_detail_texels: float = 3.0
    #: impostors remade per frame at most; those past their tolerance wait, the farthest past it first
    #: (0: no limit, every impostor past its tolerance is remade at once)
    regeneration_budget: int = 0
    #: cloud radii: full 3D below `fade_start_radii`, impostor beyond `fade_end_radii`, crossfade between
    fade_start_radii: float = 2.0
    fade_end_radii: float = 4.0
    #: per axis: the screen impostor of a cloud the eye is inside has this fraction of the screen's pixels
    inside_resolution_scale: float = 0.25
    #: the ring is rebuilt when the eye has moved this fraction of ring_radius horizontally / vertically
    ring_rebuild_horizontal: float = 0.15
    ring_rebuild_vertical: float = 0.02
    #: degrees above and below the horizon the ring covers; clouds reaching beyond stay out of it
    ring_elevation_deg: float = 30.0
    #: frames over which a rebuilt ring crossfades in
    ring_fade_frames: int = 8
    #: split clouds into layers around the objects inside them (Harris 3.1.1); off, objects are drawn
    #: with the world and clouds are depth-tested against them (the naive picture, for comparison)
    split_objects: bool = True

    def __post_init__(self):
        problems = []
        if self.mode not in MODES:
            problems.append(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if not 0.0 <= self.tolerance_deg <= 180.0:
            problems.append(f"tolerance_deg must be within [0, 180], got {self.tolerance_deg}")
        if not (self.ring_radius >= 0.0):
            problems.append(f"ring_radius must be >= 0 metres (inf for no ring), got {self.ring_radius}")
        for name in ("impostor_min_size", "impostor_max_size"):
            size = getattr(self, name)
            if not (isinstance(size, int) and 1 <= size <= 8192 and size & (size - 1) == 0):
                problems.append(f"{name} must be a power of two within [1, 8192], got {size!r}")
        if not 0.0 <= self.impostor_detail_texels < math.inf:
            problems.append(f"impostor_detail_texels must be >= 0 and finite, got {self.impostor_detail_texels}")
        if not (isinstance(self.regeneration_budget, int) and self.regeneration_budget >= 0):
            problems.append("regeneration_budget must be an integer >= 0 (0: no limit), "
                            f"got {self.regeneration_budget!r}")
        if self.impostor_min_size > self.impostor_max_size:
            problems.append("impostor_min_size must not exceed impostor_max_size")
        if not 0.0 <= self.fade_start_radii <= self.fade_end_radii < math.inf:
            problems.append("fade distances must satisfy 0 <= fade_start_radii <= fade_end_radii < inf, "
                            f"got {self.fade_start_radii} and {self.fade_end_radii}")
        if not 0.0 < self.inside_resolution_scale <= 1.0:
            problems.append(f"inside_resolution_scale must be within (0, 1], got {self.inside_resolution_scale}")
        if not (self.ring_rebuild_horizontal > 0.0 and self.ring_rebuild_vertical > 0.0):
            problems.append("ring rebuild fractions must be > 0")
        if not 0.0 < self.ring_elevation_deg < 90.0:
            problems.append(f"ring_elevation_deg must be within (0, 90), got {self.ring_elevation_deg}")
        if not (isinstance(self.ring_fade_frames, int) and self.ring_fade_frames >= 1):
            problems.append(f"ring_fade_frames must be an integer >= 1, got {self.ring_fade_frames!r}")
        if not isinstance(self.split_objects, bool):
            problems.append(f"split_objects must be true or false, got {self.split_objects!r}")
        if problems:
            raise ValueError("; ".join(problems))

    @property
    def uses_ring(self) -> bool:
        return self.mode != "full" and math.isfinite(self.ring_radius)


#: every particle every frame: the reference picture the approximations are measured against
FULL_3D = RenderSettings(mode="full")
