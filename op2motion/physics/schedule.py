"""What the servos are told over a physics run: a held pose, or a motion's goals every 8 ms.

A schedule holds rows of goals [rad] with each servo's stiffness Kp [N·m/rad] (from the P gains the goals were sent
with) and the support each row stands on. Before ``start_s`` the servos hold row 0 (the pose settles as gravity
ramps in), row k from ``start_s + k dt`` on, and the last row after the motion. ``planned`` is where the robot would
be with rigid servos: the torso attitude, centre of mass and feet of every row, placed with the fixed foot level
on the floor where it started; the verdict judges against it (a torso that turns as planned has not tilted).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.errors import InputError
from op2motion.model.servo import ServoModel
from op2motion.physics.body import Body, BodyState, placement, sole_flat
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support


@dataclass(frozen=True)
class Schedule:
    """Goals (K, 20) [rad], stiffness (K, 20) [N·m/rad] and supports (K,) from ``start_s`` [s], one row per ``dt``."""

    goals: np.ndarray
    kp: np.ndarray
    supports: tuple[str, ...]
    dt: float
    start_s: float
    base: tuple[np.ndarray, np.ndarray] | None = None

    @classmethod
    def hold(cls, goal: np.ndarray, support: str, servo: ServoModel) -> "Schedule":
        """One pose held for the whole run."""
        return cls(np.asarray(goal, dtype=float)[None], servo.kp[None], (support,), 1.0, 0.0)

    @classmethod
    def motion(cls, goals: np.ndarray, p_gains: np.ndarray, supports: tuple[str, ...], dt: float, start_s: float,
               servo: ServoModel, spec: Spec) -> "Schedule":
        """A motion: goals (K, 20) [rad] with the P gains (K, 20) they were sent with."""
        goals, p_gains = np.asarray(goals, dtype=float), np.asarray(p_gains, dtype=float)
        if goals.ndim != 2 or goals.shape[1] != len(spec.joints) or p_gains.shape != goals.shape:
            raise InputError(f"expected goals and P gains of shape (K, {len(spec.joints)}), got {goals.shape} and "
                             f"{p_gains.shape}", "motion")
        if len(supports) != len(goals) or not np.all(np.isfinite(goals)):
            raise InputError("expected finite goals and one support per row", "motion")
        for s in set(supports):
            Support.of(s)
        kp = spec.servo.duty_per_p_rad * p_gains * servo.stall_torque * servo.stiffness_scale
        return cls(goals, kp, tuple(supports), float(dt), float(start_s))

    def with_base(self, positions: np.ndarray, rotations: np.ndarray) -> "Schedule":
        """This schedule with a planned torso pose for every row (a walk: no foot stays where it started):
        positions (K, 3) [m] and rotations (K, 3, 3) in the world frame; the robot starts at row 0's."""
        from dataclasses import replace

        positions, rotations = np.asarray(positions, dtype=float), np.asarray(rotations, dtype=float)
        if positions.shape != (len(self.goals), 3) or rotations.shape != (len(self.goals), 3, 3):
            raise InputError(f"expected a torso pose per row ({len(self.goals)}), got {positions.shape} and "
                             f"{rotations.shape}", "motion")
        return replace(self, base=(positions, rotations))

    @property
    def is_motion(self) -> bool:
        """More than one row."""
        return len(self.goals) > 1

    @property
    def end_s(self) -> float:
        """When the last row is first sent [s]."""
        return self.start_s + (len(self.goals) - 1) * self.dt

    def row(self, t: float) -> int:
        """The row the servos hold at time ``t`` [s]."""
        if t < self.start_s:
            return 0
        return min(int((t - self.start_s) / self.dt + 1e-9), len(self.goals) - 1)

    def fixed_side(self) -> str:
        """The foot that stays on the floor throughout (in every row's support), else the left."""
        common = set.intersection(*(set(Support.of(s).feet) for s in self.supports))
        return "left" if "left" in common or not common else "right"


@dataclass(frozen=True)
class Planned:
    """Where each row of a schedule puts the robot with rigid servos: torso rotation (K, 3, 3), body state (K,)."""

    rot: np.ndarray
    states: tuple[BodyState, ...]
    flat_foot: str
    gap: float


def plan_rows(body: Body, schedule: Schedule) -> tuple[np.ndarray, np.ndarray, Planned]:
    """The start placement (torso position, rotation) and every row's planned state. The start follows
    :func:`.body.placement` (nothing below the floor, the lower more level sole flat); a motion's rows keep its
    fixed foot where it started; a schedule with planned torso poses (a walk) starts at, and plans, those."""
    if schedule.base is not None:
        positions, rotations = schedule.base
        states = tuple(body.state(p, r, g) for p, r, g in zip(positions, rotations, schedule.goals))
        gap = max(0.0, max(float(states[0].corners[s][:, 2].min()) for s in Support.of(schedule.supports[0]).feet))
        return positions[0], rotations[0], Planned(rotations, states, "left", gap)
    pos0, rot0, flat, gap = placement(body, schedule.goals[0], schedule.supports[0])
    if not schedule.is_motion:
        return pos0, rot0, Planned(rot0[None], (body.state(pos0, rot0, schedule.goals[0]),), flat, gap)
    side = schedule.fixed_side() if len(set(schedule.supports)) > 1 else flat
    start = body.state(pos0, rot0, schedule.goals[0]).soles[side]
    rots, states = [], []
    for goal in schedule.goals:
        pos, rot = sole_flat(body, goal, side)
        sole_pos, sole_rot = body.state(pos, rot, goal).soles[side]
        # the fixed sole where it started: rotate and move the whole body onto it
        turn = start[1] @ sole_rot.T
        rot = turn @ rot
        pos = turn @ (pos - sole_pos) + start[0]
        rots.append(rot)
        states.append(body.state(pos, rot, goal))
    return pos0, rot0, Planned(np.array(rots), tuple(states), flat, gap)
