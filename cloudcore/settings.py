"""How clouds are drawn: one settings object for the GUI, the command line and the benchmarks.

`mode` picks the representation: "full" draws every particle every frame (the
reference picture), "impostor" draws every cloud from a cached texture, "auto"
chooses per cloud, each frame, the representation predicted cheapest within
the tolerance (`cloudcore.frameplan`, with the measured `cloudcore.lod_costs`),
crossfading over `transition_frames` when it changes, and the ring beyond
`ring_radius`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MODES = ("auto", "full", "impostor")
#: the names of `cloudcore.impostors.TRANSLATION_METRICS` (kept here so settings import no geometry)
TRANSLATION_METRICS = ("parallax", "centre")


@dataclass(frozen=True)
class RenderSettings:
    mode: str = "auto"
    #: degrees of translation error past which an impostor is regenerated; see `translation_metric`.
    #: SkyWorks' default is 0.125 (0.9 of a pixel at 480 lines and 60 degrees).  1 saved an eighth of the
    #: default flythrough's cloud pass for 0.5 dB (side by side), but on a cumulus field the project was not
    #: tuned on it saved a tenth and cost 5 dB on the worst frame, 40.4 to 35.2 (docs/performance.md)
    tolerance_deg: float = 0.5
    #: "parallax": the angle between the rays to the impostor's near and far points (Harris, SkyWorks);
    #: "centre": the angle the eye has turned around the cloud's centre (stricter by about D / 2R)
    translation_metric: str = "parallax"
    #: pixels: when > 0, the tolerance is this many pixels at the screen's centre instead of tolerance_deg
    tolerance_px: float = 0.0
    #: metres: clouds wholly beyond this horizontal distance join Wang's ring of 8 impostors; inf: no ring
    ring_radius: float = 4000.0
    #: impostor texture sides, powers of two
    impostor_min_size: int = 16
    impostor_max_size: int = 512
    #: texels across the radius of a cloud's finest particle that an impostor texture must give; a finer
    #: texture only resamples smooth Gaussians, so none is made (0: the screen's resolution alone decides)
    impostor_detail_texels: float = 2.0
    #: impostors remade per frame at most; those past their tolerance wait, the farthest past it first
    #: (0: no limit, every impostor past its tolerance is remade at once)
    regeneration_budget: int = 0
    #: milliseconds the impostor updates and the cloud pass may take together, as the measured cost model
    #: predicts them; over it, regenerations wait (most urgent first) and the error drawn exceeds the
    #: tolerance by what the statistics report (0: no budget)
    frame_budget_ms: float = 0.0
    #: frames over which a cloud crossfades when auto mode changes its representation (no pop)
    transition_frames: int = 6
    #: draw interpenetrating clouds as one unit (one impostor, one sort: `cloudcore.lod_units`); off, each
    #: cloud's impostor is sorted as a whole, Harris's approximation
    group_clouds: bool = True
    #: per axis: the screen impostor of a cloud the eye is inside has this fraction of the screen's pixels
    #: (Harris's quarter).  An eighth saved 9% of the default flythrough's cloud pass for 0.45 dB, but under
    #: a stratocumulus deck, whose one unit's sphere holds the eye, it blurred its underside (4.2 dB on
    #: the worst frame; docs/performance.md)
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
    #: draw batches of plain splats as point sprites (one vertex per particle) where the picture is the
    #: same (`cloudcore.point_sprites`); off, always as quads (for comparison; docs/performance.md)
    point_sprites: bool = True

    def __post_init__(self):
        problems = []
        if self.mode not in MODES:
            problems.append(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if not 0.0 <= self.tolerance_deg <= 180.0:
            problems.append(f"tolerance_deg must be within [0, 180], got {self.tolerance_deg}")
        if self.translation_metric not in TRANSLATION_METRICS:
            problems.append(
                f"translation_metric must be one of {', '.join(TRANSLATION_METRICS)}, got {self.translation_metric!r}"
            )
        if not 0.0 <= self.tolerance_px < math.inf:
            problems.append(f"tolerance_px must be >= 0 and finite (0: use tolerance_deg), got {self.tolerance_px}")
        if not (self.ring_radius >= 0.0):
            problems.append(f"ring_radius must be >= 0 metres (inf for no ring), got {self.ring_radius}")
        for name in ("impostor_min_size", "impostor_max_size"):
            size = getattr(self, name)
            if not (isinstance(size, int) and 1 <= size <= 8192 and size & (size - 1) == 0):
                problems.append(f"{name} must be a power of two within [1, 8192], got {size!r}")
        if not 0.0 <= self.impostor_detail_texels < math.inf:
            problems.append(f"impostor_detail_texels must be >= 0 and finite, got {self.impostor_detail_texels}")
        if not (isinstance(self.regeneration_budget, int) and self.regeneration_budget >= 0):
            problems.append(
                f"regeneration_budget must be an integer >= 0 (0: no limit), got {self.regeneration_budget!r}"
            )
        if not 0.0 <= self.frame_budget_ms < math.inf:
            problems.append(f"frame_budget_ms must be >= 0 and finite (0: no budget), got {self.frame_budget_ms}")
        if self.impostor_min_size > self.impostor_max_size:
            problems.append("impostor_min_size must not exceed impostor_max_size")
        if not (isinstance(self.transition_frames, int) and self.transition_frames >= 1):
            problems.append(f"transition_frames must be an integer >= 1, got {self.transition_frames!r}")
        if not 0.0 < self.inside_resolution_scale <= 1.0:
            problems.append(f"inside_resolution_scale must be within (0, 1], got {self.inside_resolution_scale}")
        if not (self.ring_rebuild_horizontal > 0.0 and self.ring_rebuild_vertical > 0.0):
            problems.append("ring rebuild fractions must be > 0")
        if not 0.0 < self.ring_elevation_deg < 90.0:
            problems.append(f"ring_elevation_deg must be within (0, 90), got {self.ring_elevation_deg}")
        if not (isinstance(self.ring_fade_frames, int) and self.ring_fade_frames >= 1):
            problems.append(f"ring_fade_frames must be an integer >= 1, got {self.ring_fade_frames!r}")
        for name in ("split_objects", "group_clouds", "point_sprites"):
            if not isinstance(getattr(self, name), bool):
                problems.append(f"{name} must be true or false, got {getattr(self, name)!r}")
        if problems:
            raise ValueError("; ".join(problems))

    @property
    def uses_ring(self) -> bool:
        return self.mode != "full" and math.isfinite(self.ring_radius)


#: every particle every frame: the reference picture the approximations are measured against
FULL_3D = RenderSettings(mode="full")
