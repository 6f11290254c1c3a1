"""Weight shifts: a robot on two feet must bring its centre of mass over one foot before it lifts the other.

:func:`weight_shift` leans a double-support pose at the ankles, both legs together (sideways as a parallelogram,
with the hip rolls turning back by the same angle so the torso stays level and the feet flat), until the
full-inertia centre of mass it would settle at on that one foot (the compliant servos sag as the other foot
unloads: :mod:`op2motion.compliance`) stands over a chosen point of the sole. :func:`with_weight_shifts` inserts such
a pose wherever a sequence goes from two feet to one or back, aiming at the settled centre of mass of the
single-support pose, so the lifting (or landing) happens over the standing foot.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np

from ..compliance import Compliance
from ..errors import CheckFailed
from ..joints import servo_to_book
from ..kinematics import forward
from ..spec import Spec
from .waypoint import Waypoint

SHIFT_S = 1.0                  # the time a weight shift takes [s]
SHIFT_TOL_M = 1e-4             # the centre of mass lands this close to its target
MAX_LEAN_RAD = 0.6             # a shift needs less than this (34°); more means the target is out of reach
_ITERATIONS = 30
_STEP_RAD = 1e-4


def _hip_roll_sign(spec: Spec, side: str) -> float:
    """The hip-roll change that undoes an ankle-roll change (torso level): the ratio of the axes' x parts."""
    return -spec.joint(f"{side}_ank_roll").axis[0] / spec.joint(f"{side}_hip_roll").axis[0]


def _leaned(spec: Spec, servo: np.ndarray, roll: float, pitch: float) -> np.ndarray:
    """Both legs leaned by ``roll`` (torso level, feet flat) and both ankles pitched by ``pitch`` [rad]."""
    out = np.array(servo, dtype=float)
    for s in ("l", "r"):
        out[spec.joint_names.index(f"{s}_ank_roll")] += roll
        out[spec.joint_names.index(f"{s}_hip_roll")] += roll * _hip_roll_sign(spec, s)
        # the same forward lean on both legs: the pitch axes of the two ankles point opposite ways
        sign = spec.joint(f"{s}_ank_pitch").axis[1] / spec.joint("l_ank_pitch").axis[1]
        out[spec.joint_names.index(f"{s}_ank_pitch")] += pitch * sign
    return out


def settled_com(servo: np.ndarray, side: str, spec: Spec, model: Compliance | None = None) -> np.ndarray:
    """Where the full-inertia CoM of a pose would settle [m] (2,) standing on the ``side`` foot alone, in that
    sole's frame (infinite where the servos cannot hold it)."""
    points = forward(servo_to_book(np.atleast_2d(servo), side, spec), spec, "dh", full_com=True)
    return (model or Compliance(spec)).settle(points, points.com_full).com_xy[:, 0]


def weight_shift(servo: np.ndarray, side: str, spec: Spec, target_xy: Sequence[float] = (0.0, 0.0)) -> np.ndarray:
    """``servo`` (a double-support pose) leaned until the CoM it would settle at on the ``side`` foot alone is
    over ``target_xy`` [m] in that sole's frame (default: the sole's centre below the ankle)."""
    model = Compliance(spec)
    target = np.asarray(target_xy, dtype=float)
    lean = np.zeros(2)

    def com(v: np.ndarray) -> np.ndarray:
        return settled_com(_leaned(spec, servo, *v), side, spec, model)

    for _ in range(_ITERATIONS):
        now = com(lean)
        if not np.all(np.isfinite(now)):
            break
        err = target - now
        if np.linalg.norm(err) < SHIFT_TOL_M:
            return _leaned(spec, servo, *lean)
        jac = np.column_stack([(com(lean + d) - now) / _STEP_RAD for d in np.eye(2) * _STEP_RAD])
        lean = lean + np.linalg.lstsq(jac, err, rcond=None)[0]
        if np.abs(lean).max() > MAX_LEAN_RAD:
            break
    raise CheckFailed(f"cannot shift the weight over the {side} foot to ({target[0]:.3f}, {target[1]:.3f}) m by "
                      f"leaning the legs (would need more than {np.degrees(MAX_LEAN_RAD):.0f}°)")


def with_weight_shifts(waypoints: Sequence[Waypoint], spec: Spec) -> tuple[list[Waypoint], list[str]]:
    """The sequence with a weight shift inserted between a double-support pose and a single-support one (either
    way round): the double-support pose leaned until its CoM is where the single-support pose has it."""
    model = Compliance(spec)
    out, notes = [waypoints[0]], []
    for prev, nxt in zip(waypoints, waypoints[1:]):
        if (prev.support == "double") != (nxt.support == "double"):
            double, single = (prev, nxt) if prev.support == "double" else (nxt, prev)
            target = settled_com(single.servo, single.support, spec, model)
            if not np.all(np.isfinite(target)):
                raise CheckFailed(f"{single.name} cannot stand on the {single.support} foot: the servos would not "
                                  f"hold it")
            shifted = weight_shift(double.servo, single.support, spec, target)
            name = f"{double.name}@{single.support}"
            if prev.support == "double":      # shift, then lift into the single-support pose
                out.append(Waypoint(name, shifted, SHIFT_S, 0.0, "double"))
                out.append(nxt)
            else:                             # come down over the standing foot, then shift back
                out.append(Waypoint(name, shifted, nxt.duration_s, 0.0, "double"))
                out.append(replace(nxt, duration_s=SHIFT_S))
            notes.append(f"inserted a {SHIFT_S:g} s weight shift onto the {single.support} foot "
                         f"({'before' if prev.support == 'double' else 'after'} {single.name})")
        else:
            out.append(nxt)
    return out, notes
