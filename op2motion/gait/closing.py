"""Closing the feet: a robot that stopped mid-walk stands with one foot ahead of the other (the stop froze the walk on
its next double support), which no later motion can start from without sliding a sole. :func:`closing_gait` plans
the one step that brings the back foot beside the front one, with the walk's own planner
(:func:`~op2motion.gait.generator.generate_gait` given the feet where they stand and that one step: the ZMP
preview walk of the default preset, so the step is a walk's closing step, 2.4 s with its lead-in and settling;
played by a :class:`~op2motion.gait.controller.WalkController`, with its feedback: open loop, the swing foot
scuffed the floor in physics). The robot commands step so before any move from feet that stand apart
(:func:`op2motion.onrobot.tasks.close_feet`). Feet side by side (one no more than
:data:`CLOSED_M` ahead of the other, turned no more than :data:`CLOSED_RAD` from it) need no step: None; a stance
only wider or narrower than the walk's is left as it is.

Frames: soles from the leg angles in the torso frame (:func:`~op2motion.kinematics.leg_ik.leg_fk`); the plan's
world is the feet's midpoint on the floor, X along their mean heading, Y left.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from op2motion.kinematics.leg_ik import leg_fk, leg_of
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side

if TYPE_CHECKING:
    from op2motion.gait.generator import Gait
    from op2motion.gait.params import GaitParams

CLOSED_M = 0.01                    # the feet within this of the preset's stance (along and across) need no step [m]
CLOSED_RAD = math.radians(3.0)     # ... and turned within this of each other [rad]


def soles(servo: np.ndarray, spec: Spec) -> dict[Side, tuple[np.ndarray, np.ndarray]]:
    """Both soles' centres (3,) [m] and rotations (3, 3) in the torso frame for servo angles (20,) [rad]."""
    out: dict[Side, tuple[np.ndarray, np.ndarray]] = {}
    for side in ("left", "right"):
        leg = leg_of(spec, side)
        p, r = leg_fk(leg, np.asarray(servo, dtype=float)[list(leg.index)])
        out[side] = (p[0], r[0])
    return out


def yaw_of(rot: np.ndarray) -> float:
    """The heading of a rotation about Z [rad]."""
    return math.atan2(float(rot[1, 0]), float(rot[0, 0]))


def placements(servo: np.ndarray, spec: Spec) -> dict[Side, np.ndarray]:
    """Where each sole stands, (x [m], y [m], yaw [rad]) in the frame of the feet's midpoint and mean heading."""
    feet = soles(servo, spec)
    yaws = {side: yaw_of(r) for side, (_, r) in feet.items()}
    heading = 0.5 * (yaws["left"] + yaws["right"])
    mid = 0.5 * (feet["left"][0][:2] + feet["right"][0][:2])
    c, s = math.cos(heading), math.sin(heading)
    back = np.array([[c, s], [-s, c]])
    return {side: np.array([*(back @ (p[:2] - mid)), yaws[side] - heading]) for side, (p, _) in feet.items()}


@dataclass(frozen=True)
class Stance:
    """How two soles stand: the ``front`` foot, how far the other is behind it (``behind_m`` [m]), how far the feet
    are from the step width apart across (``across_m`` [m]), how far they are turned from each other
    (``turned_rad`` [rad])."""

    front: Side
    behind_m: float
    across_m: float
    turned_rad: float

    @property
    def closed(self) -> bool:
        """Side by side: no step needed (within :data:`CLOSED_M` and :data:`CLOSED_RAD`)."""
        return self.behind_m <= CLOSED_M and self.turned_rad <= CLOSED_RAD


def apart(servo: np.ndarray, spec: Spec, width_m: float) -> Stance:
    """How the soles stand for servo angles (20,) [rad], the feet meant to be ``width_m`` [m] apart across."""
    at = placements(servo, spec)
    dx, dy = at["left"][:2] - at["right"][:2]
    front: Side = "left" if dx >= 0.0 else "right"
    turned = abs(math.remainder(float(at["left"][2] - at["right"][2]), 2 * math.pi))
    return Stance(front, abs(float(dx)), abs(float(dy) - width_m), turned)


def closing_gait(servo: np.ndarray, spec: Spec, params: GaitParams) -> Gait | None:
    """The walk of one step from ``servo`` (20,) [rad], standing on both feet, to the feet side by side ``params``'
    step width apart (see the module docstring); None when they are already."""
    from op2motion.gait.footsteps import Footstep, Footsteps, foot_at, moved, step_width
    from op2motion.gait.generator import generate_gait

    width = step_width(params, spec)
    stance = apart(servo, spec, width)
    if stance.closed:
        return None
    at = placements(servo, spec)
    start: dict[str, Footstep] = {side: Footstep(side, float(p[0]), float(p[1]), float(p[2]))
                                  for side, p in at.items()}
    front = stance.front
    back: Side = "right" if front == "left" else "left"
    centre = moved(at[front], 0.0, -width / 2.0 if front == "left" else width / 2.0, 0.0)
    step = foot_at(back, centre, width)
    return generate_gait(params.with_steps(1), spec, footsteps=Footsteps(start, (step,)))

