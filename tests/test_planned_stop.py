"""A planned walk stopped early (op2motion.gait.planned_stop): the rolling planner goes on from the walk's own state
(its cart exactly), the rows run on without a jump, and the walk ends within two steps with its feet side by side.
(In physics, against the emulated OP2: tests/test_robot_cli.py.)"""

from __future__ import annotations

import numpy as np
import pytest

from op2motion.gait.closing import CLOSED_M, CLOSED_RAD, apart
from op2motion.gait.controller import WalkController
from op2motion.gait.footsteps import step_width
from op2motion.gait.planned_stop import splice_row, step_starts
from op2motion.gait.preview import CartState, preview_gains, run_cart
from op2motion.gait.rows import planned_zmp_margins
from op2motion.robot.framework import CONTROL_PERIOD_S

CART_TOL = 1e-12              # the stored preview state against the controller run again to that row [m, m/s, m/s²]
JUMP_SHARE = 1.0              # a row's largest goal change at the seam, against the walk's own largest [1]
MARGIN_FLOOR_M = -0.005       # the stop's planned ZMP stays within this of the soles (the steered stop's lift-off:
                              # -3.8 mm for three rows; the walk's own least margin is +11 mm) [m]
STEPS = 12


@pytest.fixture(scope="module")
def fresh(spec):
    def make() -> WalkController:
        return WalkController.from_preset("forward", steps=STEPS, spec=spec)
    return make


def _stopped(controller: WalkController, row: int, rows_after: int = 400) -> WalkController:
    """``controller`` told to stop at gait row ``row`` and ticked on ``rows_after`` rows with no sensors."""
    controller._k = row
    controller.stop()
    for k in range(row, row + rows_after):
        controller._stopping_rows(k)
    return controller


def test_the_gait_keeps_its_preview_state_exactly(fresh):
    gait = fresh().gait
    params = gait.params
    gains = preview_gains(CONTROL_PERIOD_S, gait.com_height, params.preview_s, params.zmp_weight, params.jerk_weight)
    row = step_starts(gait)[3]
    ref = gait.timeline.zmp_ref
    aimed = ref + gait.zmp_correction                           # the CoM path's reference, every correction added
    _, kept = run_cart(gains, aimed, len(aimed), CartState.rest(ref[0]), keep=row)
    assert np.max(np.abs(gait.cart_states[row, :3] - kept.x)) < CART_TOL
    assert np.max(np.abs(gait.cart_states[row, 3] - kept.summed)) < CART_TOL


@pytest.mark.parametrize("when", ["after the first step", "mid-walk", "three steps left"])
def test_a_stop_closes_the_feet_within_two_steps_without_a_jump(fresh, spec, when):
    controller = fresh()
    starts = step_starts(controller.gait)
    row = {"after the first step": starts[1] - 30, "mid-walk": starts[4] + 5,
           "three steps left": starts[-3] - 30}[when]
    own = controller.rows.numeric["goals"].copy()
    own_jump = np.max(np.abs(np.diff(own, axis=0)))
    _stopped(controller, row)
    first = controller.stopped_from
    assert first is not None and first - row >= 24                        # planned ahead, a stage a tick
    goals = controller.rows.numeric["goals"]
    assert np.array_equal(goals[:first], own[:first])                      # the rows played stay as they were
    assert np.max(np.abs(np.diff(goals[first - 3:], axis=0))) <= JUMP_SHARE * own_jump
    steps = [p for f, p in controller.stopper.phases if p.kind == "step"]
    assert len(steps) <= 2 and (not steps or steps[-1].closing)
    end = controller.rows.end - 1
    angles = np.zeros(len(spec.joints))
    for side in ("left", "right"):
        angles[list(controller.legs[side].index)] = controller.rows.legs(side, end)
    stance = apart(angles, spec, step_width(controller.params, spec))
    assert stance.closed and stance.behind_m <= CLOSED_M and stance.turned_rad <= CLOSED_RAD
    margin = planned_zmp_margins(controller.rows, spec, controller.rows.end)[first:]
    assert margin.min() >= MARGIN_FLOOR_M
    ends = [f for f, p in controller.stopper.phases if p.kind == "end"]
    controller._k = ends[0]
    assert not controller.done                                   # on its feet, not yet settled
    controller._k = controller.rows.end - 1
    assert controller.done


def test_a_stop_before_the_first_step_holds_the_walk_on_both_feet(fresh):
    controller = fresh()
    row = step_starts(controller.gait)[0] - 60
    controller._k = row
    controller.stop()
    assert controller.stopper is None and controller.held_row == row and controller._plan_over(row)
    held = controller._planned_goals(10.0, row)
    assert np.array_equal(held, controller.rows.get("goals", row))
    assert controller.rows.obj("contact", row) == "double"


def test_a_stop_with_two_steps_left_leaves_the_walk_as_planned(fresh):
    controller = fresh()
    starts = step_starts(controller.gait)
    row = starts[-2] - 30
    assert splice_row(controller.gait, row) is None
    own = controller.rows.numeric["goals"].copy()
    controller._k = row
    controller.stop()
    assert controller.stopper is None and np.array_equal(controller.rows.numeric["goals"], own)
