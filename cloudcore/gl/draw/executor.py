"""What a draw kind's executor is, what it is given, and the registry that finds it by its kind.

A step of the cloud pass (`DrawStep`) is one of the plan's draw kinds: "ring", "full", "crossfade",
"impostor", "inside" (the units' kinds of `cloudcore.lod.plan.KINDS`) or "object" (an object drawn between
a split cloud's layers).  Each kind has one executor, a `DrawExecutor` registered under it with `draw_kind`
(as pygfx's `register_wgpu_render_function` maps what is drawn to how it is drawn): it sorts the step's
splats (`batch`), may make something before any draw of the pass (`make_ahead`), draws the step (`draw`),
and draws it again adding 1 a fragment (`count_fragments`, the overdraw of `FrameRenderer.measure_overdraw`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.impostor_store import ImpostorStore
from cloudcore.gl.light_shafts import FrameShafts
from cloudcore.gl.objects import ObjectPass
from cloudcore.gl.quads import QuadPass
from cloudcore.gl.reduced_clouds import ReducedClouds
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.splats import SplatPass
from cloudcore.gl.volume_blending import VolumeBlendingPass
from cloudcore.lod.plan import FramePlan
from cloudcore.model.scene import Camera
from cloudcore.model.settings import RenderSettings
from cloudcore.particles.batch import SplatBatch, SplatSelection, splat_batch
from cloudcore.particles.buffer import ParticleBuffer


@dataclass(frozen=True)
class CloudPassFrame:
    """What every draw of one frame's cloud pass shares."""

    plan: FramePlan
    settings: RenderSettings
    particles: ParticleBuffer
    camera: Camera
    view: np.ndarray
    projection: np.ndarray
    view_projection: np.ndarray
    frustum: np.ndarray  # the view's planes (`cloudcore.world.camera.frustum_planes`)
    poses: tuple
    time_s: float
    splat_order: str  # splats chosen and sorted on the "cpu" or the "gpu" (the setting, "auto" resolved)
    compositing: str  # the GPU's plain full-3D splats blended by the "raster" or by "compute" ("auto" resolved)
    #: the air's volume uploaded for this eye, and the eye, that world-space quads are seen through; None: no air
    air: tuple[AirVolume, np.ndarray] | None
    context: object  # the frame's GL context and its target (`cloudcore.gl.context`)
    objects: ObjectPass | None
    shadows: CloudShadowMap | None  # the clouds' transmittance map the objects take; None: no shadows
    #: the mean blend weight of the particles of each unit (tuples of cloud indices) of a list
    unit_weights: Callable[[list], np.ndarray]
    #: where the cloud draws go: None, the frame's target; else the reduced pass (`plan.cloud_size`)
    reduced: ReducedClouds | None = None
    #: the world pass's light shafts cut at the clouds, whose share of their air every cloud's draw takes off;
    #: None: no shafts
    shafts: FrameShafts | None = None

    @property
    def eye(self) -> np.ndarray:
        return np.asarray(self.camera.position, dtype=np.float64)

    @property
    def size(self) -> tuple[int, int]:
        return self.context.width, self.context.height

    def bind_cloud_target(self) -> None:
        """Draw into the frame's target, or the reduced pass's, from now on."""
        if self.reduced is None:
            self.context.bind_target()
        else:
            self.reduced.bind()

    def batch_of(self, items) -> SplatBatch:
        """The splats of the units of draw `items`, each within its item's depth range, sorted together, seen
        through the air from the eye (their screen layers and screen impostors are made for this eye alone)."""
        clouds, depth_ranges = self.members_and_ranges(items)
        return splat_batch(self.particles, clouds, self.eye, depth_ranges, self.time_s, self.frustum, True)

    def members_and_ranges(self, items) -> tuple[tuple, tuple]:
        """(the clouds of draw `items`, the depth range of each: its item's)."""
        pairs = [(member, (item.near, item.far)) for item in items for member in self.plan.clouds[item.index].members]
        return tuple(zip(*pairs))

    def faded(self, units: list, made_at: np.ndarray) -> np.ndarray:
        """What scales each impostor of `units` made at mean blend weights `made_at`: a cloud field's fade moves
        its units' weights between the steps of their keys (`cloudcore.field.state.FADE_KEY_STEPS`), and the
        impostor follows by its opacity, in proportion.  One made at weight 0 is empty, and its key holds only
        while the weight stays 0."""
        now = self.unit_weights(units)
        return np.divide(now, made_at, out=np.zeros(len(units)), where=made_at > 0.0)


@dataclass(frozen=True, eq=False)
class DrawStep:
    """One step of the cloud pass: a run of the plan's draw items that one executor draws at once."""

    kind: str  # the executor's: "ring", "full", "crossfade", "impostor", "inside" or "object"
    items: tuple = ()  # the plan's draw items (`cloudcore.lod.plan.draw_items.DrawItem`), far to near
    batch: SplatBatch | SplatSelection | None = None  # its splats, sorted before the pass draws (`batch`)


@dataclass(frozen=True)
class DrawCounts:
    """What the draws of a pass drew, summed over its steps."""

    particles: int = 0  # particles drawn, but those of the GPU's selections: it counts them (`take_selected`)
    as_volumes: int = 0  # of them, composited as volumes (`FrameStats.particles_as_volumes`)
    compositable: int = 0  # in the GPU's draws of plain splats that either compositing way could composite

    def __add__(self, other: DrawCounts) -> DrawCounts:
        return DrawCounts(
            self.particles + other.particles,
            self.as_volumes + other.as_volumes,
            self.compositable + other.compositable,
        )


@dataclass(frozen=True)
class PassTools:
    """The GL passes the executors draw with, held by the renderer for its lifetime."""

    splats: SplatPass
    quads: QuadPass
    volume: VolumeBlendingPass
    impostors: ImpostorStore


class DrawExecutor:
    """How the steps of one draw kind are drawn.  A new kind subclasses this, names its `kind` and registers
    itself with `draw_kind`; it overrides `draw`, and `batch`, `make_ahead`, `count_fragments` where it has
    splats, makes something before the pass, or leaves fragments on the screen."""

    kind: ClassVar[str]
    #: whether its steps are made before any other draw of the pass (`make_ahead`), their splats shaded first
    made_ahead: ClassVar[bool] = False

    def __init__(self, tools: PassTools):
        self.tools = tools

    def batch(self, frame: CloudPassFrame, step: DrawStep) -> SplatBatch | SplatSelection | None:
        """The step's splats, sorted (or for the GPU to choose and sort); None: it draws none."""
        return None

    def make_ahead(self, frame: CloudPassFrame, steps: list[DrawStep]) -> None:
        """Make what the pass's `steps` of this kind need before any draw of the pass (`made_ahead` kinds)."""

    def draw(self, frame: CloudPassFrame, step: DrawStep) -> DrawCounts:
        """Draw the step into the cloud pass's target (bound); what it drew."""
        raise NotImplementedError

    def count_fragments(self, frame: CloudPassFrame, step: DrawStep) -> tuple:
        """Draw what the step left on the screen again, adding 1 a fragment into the bound counter; the splat
        batches it counted (for the analytic estimate beside the count)."""
        return ()

    def close_screen_targets(self) -> None:
        """Free the targets of the screen's size it holds (the frame's size changed, or the renderer closes)."""

    @property
    def texture_bytes(self) -> int:
        """GPU memory of the textures it holds."""
        return 0


#: every draw kind's executor class, by kind
EXECUTORS: dict[str, type[DrawExecutor]] = {}


def draw_kind(kind: str):
    """Register the decorated `DrawExecutor` subclass as the executor of the steps of `kind`."""

    def register(executor: type[DrawExecutor]) -> type[DrawExecutor]:
        if kind in EXECUTORS:
            raise ValueError(f"draw kind {kind!r} already has an executor: {EXECUTORS[kind].__name__}")
        executor.kind = kind
        EXECUTORS[kind] = executor
        return executor

    return register


def make_executors(tools: PassTools) -> dict[str, DrawExecutor]:
    """One executor of each registered draw kind, drawing with `tools`."""
    return {kind: executor(tools) for kind, executor in EXECUTORS.items()}
