"""The frame plan: what each cloud costs this frame, decided before any GL call (pure numpy).

`plan_frame` turns (the LOD units, camera, viewport, settings, the state
carried from the last frame, the lighting, measured costs) into a
`FramePlan`.  A unit (`cloudcore.lod.units`) is a cloud, or a group of clouds
whose particles interpenetrate, drawn as one; per unit one of

- ``empty``: no particles, nothing to draw;
- ``culled``: its bounding sphere misses the view frustum: no work at all;
- ``ring``: shown by Wang's ring of impostors only;
- ``full``: every particle drawn;
- ``impostor``: a textured quad, remade when `regenerate` names a reason;
- ``crossfade``: both, weights summing to one, while auto mode moves the
  unit from one representation to the other over `transition_frames` (the
  GL side mixes the two premultiplied images linearly, so the opacity is
  right throughout);
- ``inside``: the eye is in the cloud: a screen-sized impostor at reduced
  resolution, redrawn every frame (Harris 3.1); units the eye is in at once
  that follow each other in `draw_items` share one (their particles sorted
  together, one composite over the screen),

and the `LodState` to carry into the next frame.  In auto mode the choice
between full 3D and an impostor is by predicted cost within the tolerance:
an impostor's error is bounded by the tolerance (it is remade past it) and
full 3D is the reference, so both are admissible, and the plan prices each
with the measured `CostModel` (`cloudcore.lod.costs`): full 3D its particles
and fragments, the impostor its quad plus its regeneration spread over the
frames it is predicted to last at the eye's current speed.  The screen
impostor is priced the same way against the particles drawn on the screen,
and Wang's ring against its clouds drawn each on its own (`choice.ring_pays`).  What
per-unit prices miss (units drawn all in full 3D are one sorted draw) is
settled by measurement: `choice.next_frame_choice` draws a frame all in full 3D where
that measured cheaper.  The GL side executes plans and nothing else;
statistics come from the plan.

Objects inside a drawn unit's bounds split it into layers
(`cloudcore.lod.splitting`); `draw_items` is then the frame's cloud pass far to
near: unit layers, and the objects between them.  Without objects in clouds
no particle is looked at.

The stages, one module each: `pricing` (what is seen of every unit from the eye, and the work of each
representation), `choice` (auto mode's choices by price and by measured frame times), `schedule` (the
regenerations within the frame's budget), `draw_items` (the cloud pass far to near); `unit_plans` holds what was
decided per unit as arrays, `state` what persists between frames, `frame_plan` the result, `plan_stats` its
statistics, and `planner` runs the stages (`plan_frame`).  A unit out of view or held by the ring is a row of arrays;
Python looks at a unit one by one only where it is drawn on its own (docs/lod.md, "The plan at Harris's scale").
"""

from cloudcore.lod.plan.choice import SWITCH_MARGIN
from cloudcore.lod.plan.draw_items import DrawItem, DrawItems, inside_runs
from cloudcore.lod.plan.frame_plan import FramePlan
from cloudcore.lod.plan.planner import plan_frame
from cloudcore.lod.plan.state import FRAME_SETTLE_FRAMES, PROBE_FRAMES, FrameTime, LodState, Representation
from cloudcore.lod.plan.unit_plans import KINDS, TEXTURED, CloudPlan, UnitPlans

__all__ = [
    "FRAME_SETTLE_FRAMES",
    "KINDS",
    "PROBE_FRAMES",
    "SWITCH_MARGIN",
    "TEXTURED",
    "CloudPlan",
    "DrawItem",
    "DrawItems",
    "FramePlan",
    "FrameTime",
    "LodState",
    "Representation",
    "UnitPlans",
    "inside_runs",
    "plan_frame",
]
