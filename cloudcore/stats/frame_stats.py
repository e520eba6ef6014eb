"""What a frame drew and what it cost: the statistics of one `FrameRenderer.render`, typed (pure).

The plan's counts come from `FramePlan.stats` (`cloudcore.lod.plan.plan_stats.PlanStats`), the
measured times and what was drawn from the renderer, the overdraw (when measured) from
`FrameRenderer.measure_overdraw`.  Readers use the attributes; `as_dict` is
the one flat form for JSON and CSV (`cloudview render --stats`, `record`,
`bench`), whose keys are the attributes' names (the clouds per kind as
`clouds_<kind>`, the cost model's coefficients as `cost_<work>_ms`, the
overdraw's as `overdraw_<name>`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from cloudcore.lod.plan.plan_stats import PlanStats
from cloudcore.stats.overdraw import Overdraw


@dataclass(frozen=True)
class FrameStats:
    """One frame: the plan's choices, what the renderer drew, and the passes' times (what each added to the
    frame, on the CPU, on the GPU: `cloudcore.gl.pass_clock`); the defaults are an empty frame's."""

    plan: PlanStats = field(default_factory=PlanStats)
    #: shading the particles' light, and making the clouds' shadow map, when the scene, its light or the wind changed
    illumination_ms: float = 0.0
    frame_ms: float = 0.0  # planning, then world, impostor updates and cloud pass, to the frame's glFinish
    #: on the CPU before the passes: the plan, the splats' facings; auto mode prices its choices there, and on a
    #: 1.2M-particle field that once took longer than its passes
    plan_ms: float = 0.0
    world_ms: float = 0.0
    impostor_update_ms: float = 0.0
    cloud_ms: float = 0.0
    #: the CPU's part: planning, then issuing the three passes (Python, numpy, driver calls), not waiting for them
    cpu_ms: float = 0.0
    #: the GPU's time on each pass (GL_TIMESTAMP queries: `cloudcore.gl.pass_clock`)
    world_gpu_ms: float = 0.0
    impostor_update_gpu_ms: float = 0.0
    cloud_gpu_ms: float = 0.0
    particles_drawn: int = 0  # on the screen
    particles_as_points: int = 0  # of those and of the regenerations', drawn as point sprites
    particles_as_volumes: int = 0  # of those on the screen, composited as volumes (blending = "volume")
    splat_order: str = ""  # where full-3D draws and regenerations chose and sorted theirs: "cpu" or "gpu"
    compositing: str = ""  # what composited the GPU's plain full-3D splats: "raster", "compute" ("": none drawn)
    particles_to_impostors: int = 0
    clouds_drawn: int = 0
    texture_bytes: int = 0
    #: a draw composited by compute had more tile pairs than the GPU had room for (`cloudcore.gl.tile_binning`):
    #: the frame was drawn twice, both in `frame_ms` and `cpu_ms`
    drawn_again: bool = False
    overdraw: Overdraw | None = None

    @property
    def clouds_culled(self) -> int:
        return self.plan.clouds_by_kind.get("culled", 0)

    def with_overdraw(self, overdraw: Overdraw) -> FrameStats:
        return dataclasses.replace(self, overdraw=overdraw)

    def as_dict(self) -> dict:
        """The flat form: every number by name, the regeneration reasons as a dict."""
        plan = self.plan
        row = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in ("plan", "overdraw")}
        row |= {f"clouds_{kind}": count for kind, count in plan.clouds_by_kind.items()}
        row |= {
            f.name: getattr(plan, f.name) for f in dataclasses.fields(plan) if f.name not in ("clouds_by_kind", "costs")
        }
        row |= {f"cost_{name}_ms": value for name, value in dataclasses.asdict(plan.costs).items()}
        if self.overdraw is not None:
            row |= {f"overdraw_{name}": value for name, value in dataclasses.asdict(self.overdraw).items()}
        return row
