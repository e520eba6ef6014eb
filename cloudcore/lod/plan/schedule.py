"""Which of the impostors past their tolerance are remade this frame, within the frame's budget."""

from __future__ import annotations

from cloudcore.lod.costs import CostModel


def within_frame_budget(wanted, available_ms: float, costs: CostModel) -> set:
    """The wanted regenerations (index, priority, work) that fit in `available_ms`, most urgent first;
    those that must be made (rank 0: nothing to show, or layers that would cut an object) always, and
    the most urgent one at least: a budget below the frame's other work slows the picture's
    convergence (after a relight, say) but never stops it."""
    served, spent = set(), 0.0
    for index, priority, work in sorted(wanted, key=lambda w: w[1]):
        ms = costs.ms(work)
        if priority[0] == 0 or spent + ms <= available_ms or not served:
            served.add(index)
            spent += ms
    return served
