"""The cloud pass: the plan's draw items as steps, each drawn by its kind's executor, far to near.

Its recipe (`CloudPass.draw`): the steps from the plan (`draw_steps`: consecutive full-3D layers and
consecutive impostors in one step each, a run of screen impostors in one, Wang's ring first); each step's
splats sorted; all of them shaded in one go (`SplatPass.shade_ahead`: on llvmpipe each barrier is a glFinish);
the reduced pass begun; the steps made ahead (screen impostors); every step drawn; the reduced pass laid over
the screen.  The last frame's steps are kept to count their fragments (`count_fragments`).
"""

from __future__ import annotations

import dataclasses

from cloudcore.gl.draw.executor import CloudPassFrame, DrawCounts, DrawStep, PassTools, make_executors
from cloudcore.gl.reduced_clouds import ReducedClouds
from cloudcore.lod.plan import FramePlan
from cloudcore.lod.plan.draw_items import inside_runs

#: the kinds whose consecutive draw items are one step: full-3D layers interpenetrate and are sorted together;
#: a run of impostor quads is drawn with its state set once (2.6% of the untuned cumulus field's clouds side by
#: side)
_RUN_KINDS = ("full", "impostor")


def draw_steps(plan: FramePlan) -> list[tuple[str, tuple]]:
    """The cloud pass's steps in order, (kind, the draw items it draws): Wang's ring first where there is one,
    then the draw items far to near, consecutive items of `_RUN_KINDS` together, the units the eye is inside in
    their runs (`inside_runs`: one screen impostor each)."""
    steps = [("ring", [])] if plan.ring is not None else []
    inside = {run[0]: run for run in inside_runs(plan.draw_items, plan.clouds)}
    for item in plan.draw_items:
        kind = plan.clouds[item.index].kind if item.kind == "cloud" else "object"
        if kind == "inside":
            if item in inside:  # the rest of its run is in the same screen impostor
                steps.append((kind, inside[item]))
        elif kind in _RUN_KINDS and steps and steps[-1][0] == kind:
            steps[-1][1].append(item)
        else:
            steps.append((kind, [item]))
    return [(kind, tuple(items)) for kind, items in steps]


class CloudPass:
    """Executes the plan's cloud pass, one executor per draw kind (`cloudcore.gl.draw.executor`)."""

    def __init__(self, tools: PassTools):
        self._tools = tools
        self.executors = make_executors(tools)
        self.reduced: ReducedClouds | None = None  # the cloud pass at a fraction of the screen's resolution
        #: the last frame's pass and steps, whose fragments `count_fragments` counts
        self._drawn: tuple[CloudPassFrame, list[DrawStep]] | None = None

    def draw(self, frame: CloudPassFrame) -> DrawCounts:
        """Draw `frame`'s cloud pass into the frame's target (bound), or at the plan's reduced size and laid
        over it; what its draws drew."""
        executors = self.executors
        steps = []
        for kind, items in draw_steps(frame.plan):
            step = DrawStep(kind, items)
            steps.append(dataclasses.replace(step, batch=executors[kind].batch(frame, step)))
        # the steps made ahead are shaded first (a stable sort keeps the pass's order within each)
        shaded = sorted(
            (step for step in steps if step.batch is not None), key=lambda step: not executors[step.kind].made_ahead
        )
        self._tools.splats.shade_ahead([(step.batch, frame.view) for step in shaded])
        # the reduced pass reads the world's depth, and on llvmpipe the CPU then waits for the world to be drawn:
        # begun after the batches are sorted and shaded, which the world's drawing overlapped
        frame = dataclasses.replace(frame, reduced=self._reduced_pass(frame))
        for kind, executor in executors.items():
            if executor.made_ahead:
                executor.make_ahead(frame, [step for step in steps if step.kind == kind])
        frame.bind_cloud_target()
        drawn = DrawCounts()
        for step in steps:
            drawn += executors[step.kind].draw(frame, step)
        if frame.reduced is not None:
            frame.reduced.composite(frame.context)
        self._drawn = (frame, steps)
        return drawn

    def count_fragments(self) -> tuple:
        """Draw the last frame's steps again, each adding 1 a fragment into the bound counter; the splat batches
        counted."""
        frame, steps = self._drawn
        return tuple(batch for step in steps for batch in self.executors[step.kind].count_fragments(frame, step))

    @property
    def last_matrices(self) -> tuple:
        """(view, projection) of the last frame drawn."""
        return self._drawn[0].view, self._drawn[0].projection

    def _reduced_pass(self, frame: CloudPassFrame) -> ReducedClouds | None:
        """The reduced cloud pass begun for this frame at the plan's size, bound; None at the screen's size (the
        frame's target, as before)."""
        if tuple(frame.plan.cloud_size) == frame.size:
            return None
        if self.reduced is None:
            self.reduced = ReducedClouds()
        self.reduced.begin(frame.context, frame.plan.cloud_size)
        return self.reduced

    @property
    def texture_bytes(self) -> int:
        """GPU memory of the layers, screen impostors and reduced targets the pass holds."""
        held = sum(executor.texture_bytes for executor in self.executors.values())
        return held + (self.reduced.nbytes if self.reduced is not None else 0)

    def close_screen_targets(self) -> None:
        """Free the targets whose size is the frame's."""
        for executor in self.executors.values():
            executor.close_screen_targets()
        if self.reduced is not None:
            self.reduced.close()
            self.reduced = None
        self._drawn = None
