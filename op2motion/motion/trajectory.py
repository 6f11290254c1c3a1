"""A motion as the robot receives it: joint goals every 8 ms, with P gains and the support under each.

Both sources of motions produce one: a played action page (:func:`from_playback`) and a planned pose sequence
(:mod:`.planner`). Velocities and accelerations are differences of the goals [rad/s, rad/s²], which is what the
servos are asked to follow.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from op2motion.errors import InputError
from op2motion.motion.player import IDS, Playback
from op2motion.physics import Schedule
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.joints import ticks_to_servo
from op2motion.robot.spec import Spec
from op2motion.robot.support import LIFTED_M, Side, Support, SupportName


@dataclass(frozen=True)
class Trajectory:
    """Goals (K, 20) [rad] in the spec's joint order every ``dt`` [s], P gains (K, 20), the support of each row
    ("left", "right" or "double"), the segment each row belongs to (-1 for the start row) with the segments'
    names, and notes on what the planner changed (re-timing)."""

    goals: np.ndarray
    p_gains: np.ndarray
    supports: tuple[Support | SupportName, ...]
    segment: np.ndarray
    segment_names: tuple[str, ...]
    dt: float = CONTROL_PERIOD_S
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        k = len(self.goals)
        if (self.goals.ndim != 2 or self.p_gains.shape != self.goals.shape or len(self.supports) != k
                or len(self.segment) != k):
            raise InputError("expected goals, P gains, supports and segments of one length", "trajectory")

    @property
    def duration_s(self) -> float:
        """From the first goal to the last [s]."""
        return (len(self.goals) - 1) * self.dt

    @property
    def times(self) -> np.ndarray:
        """Time of each row [s] (K,)."""
        return np.arange(len(self.goals)) * self.dt

    def velocity(self) -> np.ndarray:
        """Goal velocity [rad/s] (K, 20): central differences, one-sided at the ends."""
        return np.gradient(self.goals, self.dt, axis=0) if len(self.goals) > 1 else np.zeros_like(self.goals)

    def acceleration(self) -> np.ndarray:
        """Goal acceleration [rad/s²] (K, 20)."""
        return np.gradient(self.velocity(), self.dt, axis=0) if len(self.goals) > 1 else np.zeros_like(self.goals)

    def schedule(self, spec: Spec) -> Schedule:
        """The open-loop controller that sends these goals every :attr:`dt` in physics
        (:func:`op2motion.physics.check`)."""
        return Schedule.motion(self.goals, self.p_gains, self.supports, spec, self.dt)

    def segment_of(self, row: int) -> str:
        """The name of the segment row ``row`` belongs to."""
        k = int(self.segment[row])
        return "the start" if k < 0 else self.segment_names[k]




def goal_supports(goals: np.ndarray, spec: Spec) -> tuple[SupportName, ...]:
    """The support of each row of goals (K, 20) [rad]: standing on one sole laid flat, the other foot is lifted
    when its lowest corner is more than :data:`LIFTED_M` above the floor after the servos' sag
    (:func:`.shift.settled_swing_heights`: a kick, a step); otherwise both feet stand."""
    from op2motion.motion.shift import settled_swing_heights

    lifted = {}
    pairs: tuple[tuple[Side, Side], ...] = (("left", "right"), ("right", "left"))
    for stance, swing in pairs:
        lifted[swing] = settled_swing_heights(np.atleast_2d(goals), stance, spec) > LIFTED_M
    return tuple("left" if r else "right" if le else "double" for r, le in zip(lifted["right"], lifted["left"]))


def from_playback(playback: Playback, spec: Spec, name: str = "page") -> Trajectory:
    """The goals an action page sent (IDs 1-20 in spec order), each row on the support its goals give
    (:func:`goal_supports`)."""
    order = [IDS.index(j.id) for j in spec.joints]
    goals = np.array([ticks_to_servo(row[order], spec) for row in playback.goals])
    gains = playback.p_gains[:, order].astype(float)
    segment = np.zeros(len(goals), dtype=int)
    segment[0] = -1
    return Trajectory(goals, gains, goal_supports(goals, spec), segment, (name,))
