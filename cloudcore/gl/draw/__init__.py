"""The cloud pass, one executor per draw kind: how each kind of the plan's draw items is drawn.

To add a draw kind: a module here with a `DrawExecutor` subclass registered by `@draw_kind("name")` (its
`draw`; its `batch` if it draws splats, `count_fragments` if it leaves fragments on the screen, `make_ahead`
if it must be made before the pass's other draws), imported below so that it registers; `draw_steps` gives
its draw items their kind (see docs/architecture.md, "How to add ...").
"""

from cloudcore.gl.draw import full_3d, impostors, objects, screen_impostors  # noqa: F401  (they register)
from cloudcore.gl.draw.cloud_pass import CloudPass, draw_steps
from cloudcore.gl.draw.executor import (
    EXECUTORS,
    CloudPassFrame,
    DrawCounts,
    DrawExecutor,
    DrawStep,
    PassTools,
    draw_kind,
)

__all__ = [
    "EXECUTORS",
    "CloudPass",
    "CloudPassFrame",
    "DrawCounts",
    "DrawExecutor",
    "DrawStep",
    "PassTools",
    "draw_kind",
    "draw_steps",
]
