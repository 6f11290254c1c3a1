"""A planned gait as a physics controller: the open-loop :class:`~op2motion.physics.Schedule` of its goals.

The robot starts in the plan's first pose (its planned joint angles, both soles flat), settles while gravity ramps
in (:data:`~op2motion.physics.RAMP_S` + :data:`~op2motion.gait.measures.WALK_SETTLE_S`), during which the goals move
from the planned joints to the first goals (when the servo feed-forward leads them), walks, and holds the last goal
:data:`~op2motion.gait.measures.WALK_HOLD_S`. The plan carries the torso poses and the planned contact of every row,
the walking clock the walk's measurements use, and those measurements as its hook (:mod:`op2motion.gait.measures`).
"""

from __future__ import annotations

import numpy as np

from op2motion.gait.generator import Gait
from op2motion.gait.measures import WALK_HOLD_S, WALK_SETTLE_S, walk_measures
from op2motion.physics import RAMP_S, Plan, Schedule, WalkClock
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support


def _lead(rows: np.ndarray, lead: int) -> np.ndarray:
    return np.concatenate([np.repeat(rows[:1], lead, axis=0), rows])


def plan_of_gait(gait: Gait) -> Plan:
    """The physics plan of a gait (see the module docstring)."""
    dt = gait.dt
    start = RAMP_S + WALK_SETTLE_S
    lead = int(round(start / dt))
    first, begin = gait.goals[0], gait.joints[0]
    ramp = np.minimum(1.0, np.arange(lead) * dt / RAMP_S)[:, None]
    goals = np.vstack([begin + ramp * (first - begin), gait.goals])
    steady_from, steady_to = gait.steady_window
    supports = tuple(Support.of(s) for s in gait.supports)
    contact = tuple(Support.of(s) for s in gait.timeline.contact)
    return Plan("walk", goals, _lead(gait.p_gains, lead), (supports[0],) * lead + supports, dt,
                0.0, (len(goals) - 1) * dt + WALK_HOLD_S, (_lead(gait.torso_pos, lead), _lead(gait.torso_rot, lead)),
                (contact[0],) * lead + contact,
                WalkClock(start, gait.walking_s, steady_from, steady_to), measure=walk_measures)


def gait_schedule(gait: Gait, spec: Spec) -> Schedule:
    """The open-loop controller that plays a gait's goals every 8 ms (see the module docstring)."""
    return Schedule(plan_of_gait(gait), spec.joint_names)
