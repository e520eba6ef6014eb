"""The cloud pass as steps (`cloudcore.gl.draw`): the plan's draw items grouped into the steps one executor draws
each, and every kind the plan draws with its executor; without a GL context."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.gl.draw import EXECUTORS, draw_steps
from cloudcore.lod.plan import KINDS, LodState, plan_frame
from cloudcore.lod.units import LodUnits
from cloudcore.model.scene import Camera
from cloudcore.model.settings import RenderSettings

NO_RING = RenderSettings(ring_radius=math.inf)
INSIDE_LOOK = (0.0, 0.0, -500.0)


def plan_of(centres, radii, settings=NO_RING, eye=(0.0, 0.0, 0.0), look_at=INSIDE_LOOK):
    """The plan of spheres of 1,000 splats an eighth of their radius, seen from `eye`."""
    count = len(radii)
    units = LodUnits.of_spheres(
        np.array(centres, dtype=float),
        np.array(radii, dtype=float),
        None,
        [1000.0] * count,
        [1000.0 * (r / 8.0) ** 2 for r in radii],
    )
    return plan_frame(units, Camera(eye, look_at, 60.0), (640, 480), settings, LodState(), 1)


def steps_of(plan) -> list[tuple[str, list[int]]]:
    return [(kind, [item.index for item in items]) for kind, items in draw_steps(plan)]


ROW = ((0.0, 0.0, -2000.0), (0.0, 0.0, -3000.0), (0.0, 0.0, -4000.0))


@pytest.mark.parametrize("mode", ["full", "impostor"])
def test_consecutive_full_layers_and_consecutive_impostors_are_one_step(mode):
    plan = plan_of(ROW, (100.0,) * 3, dataclasses.replace(NO_RING, mode=mode))
    assert [cloud.kind for cloud in plan.clouds] == [mode] * 3
    assert steps_of(plan) == [(mode, [2, 1, 0])]  # far to near


def test_a_run_of_units_the_eye_is_in_is_one_step_and_an_impostor_between_parts_them():
    both = plan_of(((0.0, 0.0, 20.0), (0.0, 0.0, -30.0)), (100.0, 100.0))
    assert steps_of(both) == [("inside", [1, 0])]
    parted = plan_of(
        ((0.0, 0.0, 10.0), (0.0, 0.0, -30.0), (0.0, 0.0, 60.0)),
        (100.0, 5.0, 100.0),
        dataclasses.replace(NO_RING, mode="impostor"),
    )
    assert [c.kind for c in parted.clouds] == ["inside", "impostor", "inside"]
    assert steps_of(parted) == [("inside", [2]), ("impostor", [1]), ("inside", [0])]


def test_wang_s_ring_is_drawn_first():
    plan = plan_of(ROW, (100.0,) * 3, RenderSettings(ring_radius=1000.0, mode="impostor"))
    assert plan.ring is not None
    assert steps_of(plan) == [("ring", []), ("impostor", [2, 1, 0])]


def test_every_kind_the_plan_draws_has_its_executor():
    drawn = set(KINDS) - {"empty", "culled"}  # the plan draws every other kind; objects go between layers
    assert set(EXECUTORS) == drawn | {"object"}
    assert all(executor.kind == kind for kind, executor in EXECUTORS.items())
