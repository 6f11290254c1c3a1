"""The open-loop controller, :class:`Schedule`: it ignores its sensors and sends the plan's goals row by row. A held
pose, a planned motion, a played action page and a planned gait are each a schedule.

The controller contract itself (:class:`~op2motion.robot.controller.Controller`, its hooks and the goal merger both
loops use) lives in :mod:`op2motion.robot.controller`, below the physics, so that the robot's loop needs none of it;
it is named here too, where the physics' users have always found it.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.physics.plan import DEFAULT_SECONDS, Plan
from op2motion.robot.controller import NO_HOOKS, Controller, ControllerHooks, GoalMerger, Goals, hooks_of
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, SupportName

__all__ = ["NO_HOOKS", "Controller", "ControllerHooks", "GoalMerger", "Goals", "Schedule", "check_goals", "hooks_of"]


def check_goals(goals: np.ndarray, spec: Spec, param: str = "goals") -> np.ndarray:
    """Goals as rows (K, 20) [rad] in the spec's joint order, finite."""
    goals = np.asarray(goals, dtype=float)
    if goals.ndim == 1:
        goals = goals[None]
    if goals.ndim != 2 or goals.shape[1] != len(spec.joints) or not np.all(np.isfinite(goals)):
        raise InputError(f"expected finite goals of shape (K, {len(spec.joints)}), got {goals.shape}", param)
    return goals


class Schedule:
    """The open-loop controller: the plan's goals, row by row (:meth:`.plan.Plan.row`), sensors ignored."""

    def __init__(self, plan: Plan, joint_names: Sequence[str]):
        if plan.goals.shape[1] != len(joint_names):
            raise InputError(f"expected goals for {len(joint_names)} joints, got {plan.goals.shape[1]}", "goals")
        self.plan = plan
        self.joint_names = tuple(joint_names)
        self._t = 0.0

    @classmethod
    def hold(cls, servo: np.ndarray, support: Support | SupportName, spec: Spec, seconds: float = DEFAULT_SECONDS,
             p_gains: np.ndarray | None = None) -> "Schedule":
        """One pose, servo angles (20,) [rad] in the spec's joint order, held on ``support`` for ``seconds``; the
        servos' P gains (20,) default to the spec's."""
        servo = check_goals(servo, spec, "servo angles")[0]
        gains = np.full(len(spec.joints), spec.servo.p_gain_default) if p_gains is None else p_gains
        return cls(Plan.hold(servo, support, seconds, gains), spec.joint_names)

    @classmethod
    def motion(cls, goals: np.ndarray, p_gains: np.ndarray, supports: Sequence[Support | SupportName], spec: Spec,
               dt: float = CONTROL_PERIOD_S) -> "Schedule":
        """A motion: goals (K, 20) [rad] every ``dt`` [s] with the P gains (K, 20) they were sent with, each row on
        its support (see :meth:`.plan.Plan.motion`)."""
        goals = check_goals(goals, spec)
        return cls(Plan.motion(goals, p_gains, tuple(supports), dt), spec.joint_names)

    def goals_at(self, t_s: float) -> np.ndarray:
        """The goals (20,) [rad] the schedule sends at ``t_s`` [s]."""
        goals: np.ndarray = self.plan.goals[self.plan.row(t_s)]
        return goals

    def _named(self, row: np.ndarray) -> dict[str, float]:
        return dict(zip(self.joint_names, row.tolist()))

    def start(self, joint_positions: Goals) -> Goals:
        """Row 0's goals."""
        self._t = 0.0
        return self._named(self.plan.goals[0])

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray, joint_positions: Goals) -> Goals:
        """The row of ``t_s``'s goals (the sensors are ignored)."""
        self._t = t_s
        return self._named(self.goals_at(t_s))

    @property
    def done(self) -> bool:
        """The last row has been sent."""
        return self._t >= self.plan.end_s
