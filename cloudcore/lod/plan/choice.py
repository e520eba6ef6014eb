"""Auto mode's choices: the cheaper representation of a unit within a margin, its crossfade, whether the ring
pays, which groups are planned apart, and whether a frame is drawn as its units are priced or all in full 3D by the
frames' measured times."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from cloudcore.lod.costs import CostModel
from cloudcore.lod.impostors import (
    INSIDE_RADII,
)
from cloudcore.lod.plan.draw_items import full_runs
from cloudcore.lod.plan.pricing import LONGEST_LIFETIME_FRAMES, Seen, impostor_ms_of
from cloudcore.lod.plan.state import (
    FRAME_SETTLE_FRAMES,
    MEASUREMENT_AGE_FRAMES,
    PLAUSIBLE_RATIO,
    PROBE_FRAMES,
    RING_PRICE_CHANGE_SHARE,
    RING_PRICE_FRAMES,
    RING_PRICE_MOVE_SHARE,
    RING_PRICE_TURN_DEG,
    LodState,
    Representation,
    RingPrices,
)
from cloudcore.lod.plan.unit_plans import (
    FULL,
    IMPOSTOR,
)
from cloudcore.lod.ring import (
    SEGMENTS,
    RingState,
    rebuild_pace,
)
from cloudcore.lod.units import LodUnits
from cloudcore.model.settings import AUTO_SCALE, RenderSettings

#: auto mode switches a unit's representation only when the other is cheaper by this fraction
#: (costs measured frame to frame wobble; without it a unit near the break-even point would flicker
#: between the two, paying for a crossfade each time)
SWITCH_MARGIN = 0.25


#: a scene whose particles changed by more than this factor (another scene opened, clouds added) is measured
#: afresh
SCENE_CHANGE_RATIO = 1.25


def prices_units(settings: RenderSettings) -> bool:
    """Whether the plan prices its units: full 3D draws every unit in view whatever it costs, so it does not, unless
    it chooses its cloud pass's scale by price (`cloud_pass_scale`)."""
    return settings.mode != "full" or settings.cloud_resolution_scale == AUTO_SCALE


def cheapest(held: str | None, prices: dict) -> str:
    """The name of the cheapest of `prices` (name -> ms; ties to the first), but the one `held` already
    while no other is cheaper by `SWITCH_MARGIN`: costs measured frame to frame wobble, and a choice
    near the break-even point would otherwise flicker, paying for a transition each time."""
    cheapest = min(prices, key=prices.get)
    if held in prices and prices[cheapest] >= (1.0 - SWITCH_MARGIN) * prices[held]:
        return held
    return cheapest


#: `represent_units`' codes for a representation's target
_NONE, _FULL, _IMPOSTOR = -1, 0, 1


def represent_units(
    members: tuple,
    rows,
    distances,
    priced,
    prices,
    previous: Mapping,
    held_errors,
    tolerance: float,
    all_full: bool,
    settings,
) -> tuple[np.ndarray, dict, list]:
    """Auto mode's next step for each unit at `rows` (at `distances`) that it prices on its own (`priced`, a
    mask of the rows; the others, fading into or out of the ring, are impostors: weight 0) by `prices` (a
    `RepresentationPrices`): (their full-3D weights, their representations by members, their (index, distance,
    full ms, impostor ms)).  `previous`: the representations of the last frame; `held_errors`: of the impostors
    held, per row; `all_full`: the frame heads all to full 3D (`next_frame_choice`).

    Each unit aims at the cheaper representation (`cheapest`: by `SWITCH_MARGIN` against the one aimed at
    already) and moves its full-3D weight one transition step toward it.  A unit seen for the first time starts
    at its target: there is nothing on screen to pop from; nor does a switch to a representation that shows the
    same picture within half the tolerance (an impostor within half its tolerance of full 3D, or one remade from
    this very eye): it is made at once, and only a switch that would show a step crossfades; heading `all_full`,
    an impostor within the tolerance switches at once (its step is no more than a regeneration's).
    """
    weights = np.zeros(len(rows))
    at = np.flatnonzero(priced)
    units = [members[row] for row in rows[at].tolist()]
    held = [previous.get(unit) for unit in units]
    # the eye has left a unit it was inside: its particles were on screen, as full 3D's
    was = np.array(
        [_NONE if h is None else _IMPOSTOR if h.target == "impostor" else _FULL for h in held], dtype=np.int64
    )
    was_weight = np.array([0.0 if h is None else 1.0 if h.target == "inside" else h.full_weight for h in held])
    full_ms, impostor_ms = prices.full_ms[at], np.full(len(at), math.inf) if all_full else prices.impostor_ms[at]
    keep = 1.0 - SWITCH_MARGIN
    target = np.where(
        was == _NONE,
        np.where(full_ms <= impostor_ms, _FULL, _IMPOSTOR),
        np.where(
            was == _FULL,
            np.where(impostor_ms < keep * full_ms, _IMPOSTOR, _FULL),
            np.where(full_ms < keep * impostor_ms, _FULL, _IMPOSTOR),
        ),
    )
    budgeted = bool(settings.regeneration_budget or settings.frame_budget_ms)
    errors = held_errors[at]
    # the frame heading all to full 3D (a measured choice, made again at most every `MEASUREMENT_AGE_FRAMES`), an
    # impostor within the tolerance steps to full 3D by no more than a regeneration would: at once, where a
    # crossfade's screen layer each doubled the switch's frames (the churning field's cloud pass: 100-137 ms
    # against 50 for 6 frames)
    to_full = (1.0 if all_full else 0.5) * tolerance
    close = np.where(
        target == _FULL,
        errors <= to_full,
        (errors <= 0.5 * tolerance) | ((errors > tolerance) & (not budgeted)),
    )
    at_once = (was == _NONE) | ((target != was) & close & ((was_weight == 0.0) | (was_weight == 1.0)))
    step = 1.0 / settings.transition_frames
    stepped = np.where(target == _FULL, np.minimum(1.0, was_weight + step), np.maximum(0.0, was_weight - step))
    weight = np.where(at_once, np.where(target == _FULL, 1.0, 0.0), stepped)
    weights[at] = weight
    # a unit's representation as it was is kept, not made anew: most units keep theirs from frame to frame
    chosen = {
        unit: h if h is not None and h.target == name and h.full_weight == w else Representation(name, w)
        for unit, h, name, w in zip(
            units, held, ["full" if t == _FULL else "impostor" for t in target.tolist()], weight.tolist()
        )
    }
    prices_of = list(zip(rows[at].tolist(), distances[at].tolist(), full_ms.tolist(), prices.impostor_ms[at].tolist()))
    return weights, chosen, prices_of


def ring_pays(state: RingState, ring_ms: float, alone_ms: float) -> bool:
    """Whether the ring should hold its clouds: the cheaper of the two (`cheapest`: each switch rebuilds
    the ring and crossfades it)."""
    newest = state.pending or state.current
    held = None if newest is None else "ring" if newest.holds_clouds else "alone"
    return cheapest(held, {"ring": ring_ms, "alone": alone_ms}) == "ring"


def ring_outrun(state: RingState, step, tolerance_deg: float, settings: RenderSettings) -> bool:
    """Whether the eye outruns Wang's ring, whose clouds impostor mode then draws each from its own impostor: the
    eye's `step` (3,) this frame moves a panel's picture of a cloud far beyond it past `tolerance_deg` (about s / R
    radians after a step s: `ring_translation_error`), and the last ring that held clouds lasted no longer than its
    rebuild takes at this pace (`rebuild_pace`): rebuilt without end, each ring past the tolerance once shown.  The
    cumulus field's flight sampled 160 m a frame rebuilt its whole ring every frame, at more cost than its clouds'
    own impostors and further from full 3D (docs/performance.md, "The field's impostors within 35 dB"); at flying
    speeds (under 35 m a frame at the default radius and tolerance), or after a single jump, the ring is held as
    before."""
    moving = float(np.linalg.norm(np.asarray(step, dtype=np.float64)))
    if moving <= math.radians(tolerance_deg) * settings.ring_radius:
        return False
    pace = rebuild_pace(step, settings)
    return state.rebuild_interval <= math.ceil(SEGMENTS / pace.segments_a_frame) + pace.fade_frames


def ring_prices_hold(
    prices: RingPrices | None, units, eye, back, in_view: int, state: LodState, settings, costs: CostModel
) -> bool:
    """Whether the ring's last `prices` still stand for the frame of `units` seen from `eye` looking along -`back`
    (the view's third row), `in_view` of its clouds in view, priced by `costs`: the same units and ring newest,
    priced fewer than `RING_PRICE_FRAMES` frames ago, the count in view and each coefficient of the model within
    `RING_PRICE_CHANGE_SHARE` of theirs then, and the view near the one priced (turned less than
    `RING_PRICE_TURN_DEG`, moved less than `RING_PRICE_MOVE_SHARE` of a rebuild distance).
    The ring's clouds are beyond its radius: what they cost drawn either way changes slowly with the view, and
    the choice between the two has a margin; pricing them is most of what auto mode's plan adds to impostor
    mode's where the ring holds thousands of clouds."""
    if (
        prices is None
        or prices.units is not units
        or prices.generation is not (state.ring.pending or state.ring.current)
        or state.frame_index - prices.frame_index >= RING_PRICE_FRAMES
        or abs(in_view - prices.in_view) > RING_PRICE_CHANGE_SHARE * prices.in_view
        or np.any(np.abs(costs.vector() - prices.costs.vector()) > RING_PRICE_CHANGE_SHARE * prices.costs.vector())
    ):
        return False
    moved = np.asarray(eye, dtype=np.float64) - prices.eye
    turned = float(np.dot(back, prices.back)) < math.cos(math.radians(RING_PRICE_TURN_DEG))
    return not turned and (
        math.hypot(moved[0], moved[2])
        <= RING_PRICE_MOVE_SHARE * settings.ring_rebuild_horizontal * settings.ring_radius
        and abs(moved[1]) <= RING_PRICE_MOVE_SHARE * settings.ring_rebuild_vertical * settings.ring_radius
    )


def groups_cheaper_apart(units: LodUnits, seen: Seen, settings, state: LodState, costs, focal_px: float) -> frozenset:
    """The groups of interpenetrating clouds (their members) that auto mode would rather plan apart, each cloud a
    unit of its own (`LodUnits.apart_rows`): while the eye moves, those whose clouds' impostors cost less than the
    group's (`cheapest`, held apart while so).

    A group's impostor is the picture without the blobs of clouds sorted whole (`cloudcore.lod.units`); a
    moving eye remakes it every particle at a time, and sooner than its clouds' (its sphere is larger: more
    parallax for the same step).  Moving, the blobs are the price of the time saved (`RenderSettings.
    groups_apart_in_motion`); still (the group's impostor would outlast `LONGEST_LIFETIME_FRAMES`), or with
    the eye in its sphere, a group is whole, whatever the prices: it closes, remade from that very eye.
    `plan_frame` opens a group only where its own impostor is due anyway.  `seen`: the `seen_from` of
    `units.and_clouds`.
    """
    groups, group_seen = units.groups, seen.take(units.group_rows)
    # a group whose sphere holds the eye is whole: its screen impostor draws its particles sorted together, as
    # full 3D does, and apart its clouds would cost as much (the particles near the eye are the screen
    # impostor's cost, whatever holds them; under a stratocumulus deck apart was 1.7 times dearer)
    outside = group_seen.distances >= INSIDE_RADII * groups.radii
    moving = group_seen.lifetimes < LONGEST_LIFETIME_FRAMES
    candidates = outside & moving
    if not candidates.any():  # a still eye: nothing more to price
        return frozenset()
    # the candidates' impostors and their clouds' (the rows of `units.and_clouds` after the units) priced in one pass
    # (a cloud whose own sphere holds the eye is priced as a quad over the whole screen: dear, so its group stays);
    # the clouds' units are the groups' members in order
    group_rows = units.group_rows[candidates]
    impostors_ms = impostor_ms_of(
        units.and_clouds,
        seen,
        np.concatenate([group_rows, np.arange(len(units.members), len(seen.distances))]),
        focal_px,
        settings,
        costs,
    )
    group_ms, part_ms = impostors_ms[: len(group_rows)], impostors_ms[len(group_rows) :]
    apart_ms = np.add.reduceat(part_ms, np.cumsum(groups.member_counts) - groups.member_counts)[candidates]
    indices = np.flatnonzero(candidates).tolist()
    held_apart = np.fromiter((groups.members[i] in state.opened for i in indices), dtype=bool, count=len(indices))
    # `cheapest` of the two, group by group: the way held unless the other is cheaper by the margin
    keep = 1.0 - SWITCH_MARGIN
    apart = np.where(held_apart, group_ms >= keep * apart_ms, apart_ms < keep * group_ms)
    return frozenset(groups.members[i] for i in np.asarray(indices, dtype=np.int64)[apart].tolist())


def units_ms(unit_prices, ring_ms: float, alone_ms: float, candidates, costs: CostModel) -> float:
    """The predicted time of a frame of units each in the representation its own price picks.

    The units' prices (`unit_prices`: (index, distance, full 3D ms, the other's ms) of the units planned
    on their own) miss that full units between impostors are drawn in as many batches as there are
    runs; the ring's candidates in view (`candidates`) count as the cheaper of the ring (`ring_ms`)
    and their own prices (`alone_ms`).
    """
    priced_ms, kinds = 0.0, []
    for index, _, full_ms, other_ms in sorted(unit_prices, key=lambda price: -price[1]):
        if not candidates[index]:
            priced_ms += min(full_ms, other_ms)
        kinds.append(FULL if full_ms <= other_ms else IMPOSTOR)
    ring_part = min(ring_ms, alone_ms) if candidates.any() else 0.0
    return priced_ms + ring_part + costs.batches * full_runs(np.array(kinds, dtype=np.int8))


def comparable(before: float, now: float) -> bool:
    """Whether a scene of `now` particles is the one of `before` for what was measured of it."""
    return before > 0.0 and now > 0.0 and max(before, now) <= SCENE_CHANGE_RATIO * min(before, now)


def known(state: LodState, choice: str) -> bool:
    """Whether the frames drawn as `choice` have been measured for long enough, recently enough, to choose by."""
    time = state.frame_times.get(choice)
    frame = state.frame_index + 1  # the frame being planned
    return time is not None and time.frames >= PROBE_FRAMES and frame - time.last_frame <= MEASUREMENT_AGE_FRAMES


def settled_in_full_3d(state: LodState) -> bool:
    """Auto mode draws every unit in full 3D, settled there (`FRAME_SETTLE_FRAMES` drawn so, or sooner once no unit
    and no ring is still on its way there), and has measured the units' way freshly: the frame can be planned as
    full mode plans it, without pricing a unit.  Priced, a frame of the cumulus field all in full 3D planned in
    2.6 ms where full mode's plan took 0.7; a switch made at once (`represent_units`, `plan_ring`'s `at_once`) is
    settled in its next frame."""
    if not (state.frame_choice == state.drawn_as == "full" and known(state, "units")):
        return False
    if state.frames_drawn_as > FRAME_SETTLE_FRAMES:
        return True
    ring = state.ring
    return (ring.pending is None and (ring.current is None or not ring.current.holds_clouds)) and all(
        held.target == "full" and held.full_weight == 1.0 for held in state.representations.values()
    )


def next_frame_choice(state: LodState, drawn_as: str, predicted: Callable[[], dict]) -> str:
    """How auto mode draws the next frame: "units" or "full" (`LodState.frame_choice`), by the measured times
    of both (`cheapest`, within its margin), once both are measured and fresh; the way this frame was drawn
    while it is being measured; the other, to measure it, where its `predicted` time is plausibly close.
    The choice acts through each unit's representation and the ring, so a switch crossfades; `predicted()`
    gives the predicted times of both, asked only for the last."""
    other = "full" if drawn_as == "units" else "units"
    if not known(state, drawn_as):
        return drawn_as
    if known(state, other):
        return cheapest(drawn_as, {choice: state.frame_times[choice].mean_ms for choice in (drawn_as, other)})
    times = predicted()
    return other if times[other] < PLAUSIBLE_RATIO * times[drawn_as] else drawn_as


def cloud_pass_scale(held_scale: float | None, screen_ms: float, reduced_ms: float, scale: float) -> float:
    """The cloud pass's scale this frame: `scale` where its pass (`reduced_ms`, `pricing.reduced_pass_work`) is
    cheaper than the pass at the screen's resolution (`screen_ms`), else 1; the scale `held_scale` last frame while
    the other is not cheaper by `SWITCH_MARGIN` (the picture changes a little at each switch)."""
    held = None if held_scale is None else ("reduced" if held_scale < 1.0 else "screen")
    return scale if cheapest(held, {"screen": screen_ms, "reduced": reduced_ms}) == "reduced" else 1.0
