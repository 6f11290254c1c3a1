"""Stopping a planned walk early: within two steps, the feet side by side, standing.

A planned walk (:class:`~.controller.WalkController`) sees every footstep before the first; stopped before its end
(Ctrl-C on the robot), it goes on with the rolling planner of the steered walk (:mod:`.rolling`) from the first step
that begins at least :data:`~.rolling.PLAN_AHEAD_ROWS` rows (192 ms) later: there, between two steps, the
planner takes over the walk's state (where the feet stand, the body's path, the foot to swing next), its last
rows, the preview controller's cart (the planned CoM path's state and summed error, :func:`.generator.cart_states`)
and the multibody corrections of the ZMP reference, so the CoM path runs on without a seam. From there it stops
as a steered walk does (:mod:`.phases`): a step at half the stride (from a long one), the closing step that puts the
swing foot beside the other, the end's double support; the rows are replaced from that step on, in the
controller's own buffer, a planning stage a tick. (Closing at once from a full stride, as the planned walk's own last
step does with the whole preview ahead, left the planned ZMP 63 mm outside the sole: the preview had 0.3 s to
prepare.) A stop before the first step holds the walk where it is, on both feet (the controller's
:meth:`~.controller.WalkController.stop`: the planner's standing after the start's weight shift jolted the servos'
feed-forward); one with two steps left or fewer changes nothing: the walk closes its feet by itself as soon.

Frames: the planned walk's world (the start's: X forward, Y left, floor at Z = 0); rows are the gait's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.gait.envelope import STEER_ENVELOPE, Stride
from op2motion.gait.footsteps import Footstep, moved, step_width
from op2motion.gait.phases import WalkState
from op2motion.gait.preview import CartState
from op2motion.gait.rolling import HISTORY_ROWS, PLAN_AHEAD_ROWS, History, RollingPlanner, Seed
from op2motion.gait.rows import RowBuffer
from op2motion.kinematics.leg_ik import Leg
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES, Side

if TYPE_CHECKING:
    from op2motion.gait.generator import Gait


def step_starts(gait: Gait) -> list[int]:
    """The gait row each step's single support begins at, in order."""
    step = gait.timeline.step
    return [int(np.argmax(step == j)) for j in range(len(gait.footsteps.steps))]


def splice_row(gait: Gait, row: int) -> tuple[int, int] | None:
    """(the step, its first row) a stop asked at gait row ``row`` takes over from: the first step beginning at
    least :data:`~.rolling.PLAN_AHEAD_ROWS` later; None when the walk has no more than two steps left from there."""
    starts = step_starts(gait)
    earliest = max(row, 0) + PLAN_AHEAD_ROWS
    j = next((j for j, first in enumerate(starts) if first >= max(earliest, HISTORY_ROWS)), None)
    if j is None or j >= len(starts) - 2:
        return None
    return j, starts[j]


def _centre(step: Footstep, width: float) -> np.ndarray:
    """The body path's pose (x [m], y [m], yaw [rad]) a foot placed at ``step`` stands beside (half the step
    width to its side)."""
    half = width / 2.0 if step.side == "left" else -width / 2.0
    return moved(np.array([step.x, step.y, step.yaw]), 0.0, -half, 0.0)


def state_before(gait: Gait, j: int, first: int, width: float) -> WalkState:
    """The walk between step ``j - 1`` and step ``j`` (``j`` >= 1, which begins at gait row ``first``) as the
    rolling planner keeps it."""
    feet = {side: gait.timeline.feet[side][first - 1] for side in SIDES}
    placed = {side: Footstep(side, float(f[0]), float(f[1]), float(f[3])) for side, f in feet.items()}
    steps = gait.footsteps.steps
    swing: Side = steps[j].side
    centre = _centre(steps[j - 1], width)
    before = _centre(steps[j - 2], width) if j >= 2 else np.zeros(3)
    c, s = np.cos(before[2]), np.sin(before[2])
    d = centre[:2] - before[:2]
    stride = Stride(float(c * d[0] + s * d[1]), float(-s * d[0] + c * d[1]), float(centre[2] - before[2]))
    return WalkState(placed["left"], placed["right"], (float(centre[0]), float(centre[1]), float(centre[2])),
                     stride, swing, "walk", first, 0, False, j)


def seed_at(gait: Gait, rows: RowBuffer, first: int, state: WalkState) -> Seed:
    """What the rolling planner goes on from at gait row ``first`` of ``gait`` (see the module docstring); its
    ``rows`` (the walk controller's) are cut there."""
    if gait.cart_states is None or gait.zmp_correction is None:
        raise Op2MotionError("a gait without its preview states cannot be planned on")
    before = slice(first - HISTORY_ROWS, first)
    t = gait.timeline
    history = History({s: t.feet[s][before].copy() for s in SIDES}, t.contact[before], gait.torso_pos[before].copy(),
                      gait.torso_rot[before].copy(), gait.joints[before].copy(), t.zmp_ref[before].copy())
    cart = CartState(gait.cart_states[first, :3].copy(), gait.cart_states[first, 3].copy())
    rows.truncate(first)
    return Seed(state, rows, history, cart, gait.zmp_correction[first:].copy(), gait.com_height)


def stop_planner(gait: Gait, spec: Spec, legs: Mapping[str, Leg], rows: RowBuffer, step: int, first: int
                 ) -> RollingPlanner:
    """The rolling planner that stops ``gait``'s walk from its step ``step`` (>= 1) on, which begins at gait row
    ``first`` (:func:`splice_row`; see the module docstring), extending the walk controller's ``rows`` in place."""
    state = state_before(gait, step, first, step_width(gait.params, spec))
    planner = RollingPlanner(gait.params, spec, STEER_ENVELOPE, legs, seed=seed_at(gait, rows, first, state))
    planner.keep_all = True                          # (short: the rows from the walk's start stay, for its odometry)
    planner.stop()
    return planner
