"""Weight shifts: a robot on two feet must bring its centre of mass over one foot before it lifts the other.

:func:`weight_shift` leans a double-support pose at the ankles, both legs together (sideways as a parallelogram,
with the hip rolls turning back by the same angle so the torso stays level and the feet flat), until the
full-inertia centre of mass it would settle at on that one foot (the compliant servos sag as the other foot
unloads: :mod:`op2motion.model.compliance`) stands over a chosen point of the sole. :func:`with_weight_shifts`
inserts such a pose wherever a sequence goes from two feet to one or back, aiming at the settled centre of mass of the
single-support pose, so the lifting (or landing) happens over the standing foot.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np

from op2motion.errors import CheckFailed
from op2motion.kinematics import forward
from op2motion.kinematics.dh import MATRIX_BELOW, forward_dh_frames
from op2motion.kinematics.points import ROW
from op2motion.model.compliance import Compliance, SwingLegSag
from op2motion.motion.waypoint import Waypoint
from op2motion.robot.joints import hip_roll_sign, servo_to_book
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support, as_side

SHIFT_S = 1.0                  # the time a weight shift takes [s]
SHIFT_TOL_M = 1e-4             # the centre of mass lands this close to its target
LIFT_S = 1.2                   # the time lifting the swing foot off the floor takes [s]
LIFT_CLEAR_M = 0.015           # ... to this height of its lowest corner above the floor, after the sag [m]
TOUCH_CLEAR_M = 0.003          # coming down, the foot first stops this high, then takes the load slowly [m]
SHIFT_EDGE_M = 0.035           # a weight shift aims at least this far inside the sole's edges [m]: at 25 mm the
#                                lean onto book_2_44 (CoM 21 mm out of the ankle) tipped over the outer edge
LIFT_ABDUCT_RAD = 0.1          # the lifted leg turns this far outward at the hip (6°, about 20 mm at the foot)
MAX_FOLD_RAD = 1.2             # a lift folds the knee by at most twice this
MAX_LEAN_RAD = 0.6             # a shift needs less than this (34°); more means the target is out of reach
_ITERATIONS = 30
_STEP_RAD = 1e-4


def _leaned(spec: Spec, servo: np.ndarray, roll: np.ndarray | float, pitch: np.ndarray | float) -> np.ndarray:
    """Poses (..., 20) with both legs leaned by ``roll`` (torso level, feet parallel) and both ankles pitched by
    ``pitch`` [rad] (scalars or one per pose)."""
    out = np.array(servo, dtype=float)
    for s in ("l", "r"):
        out[..., spec.joint_names.index(f"{s}_ank_roll")] += roll
        out[..., spec.joint_names.index(f"{s}_hip_roll")] += np.multiply(roll, hip_roll_sign(spec, s))
        # the same forward lean on both legs: the pitch axes of the two ankles point opposite ways
        sign = spec.joint(f"{s}_ank_pitch").axis[1] / spec.joint("l_ank_pitch").axis[1]
        out[..., spec.joint_names.index(f"{s}_ank_pitch")] += np.multiply(pitch, sign)
    return out


def settled_coms(servo: np.ndarray, side: Support | Side, spec: Spec, model: Compliance | None = None) -> np.ndarray:
    """Where the full-inertia CoM of poses (N, 20) would settle [m] (N, 2) standing on the ``side`` foot alone, in
    that sole's frame (infinite where the servos cannot hold it)."""
    points = forward(servo_to_book(np.atleast_2d(servo), side, spec), spec, "dh", full_com=True)
    return (model or Compliance(spec)).settle(points, points.full()).com_xy.T


def settled_com(servo: np.ndarray, side: Support | Side, spec: Spec, model: Compliance | None = None) -> np.ndarray:
    """:func:`settled_coms` of one pose (20,): [m] (2,)."""
    com: np.ndarray = settled_coms(servo, side, spec, model)[0]
    return com


def weight_shift(servo: np.ndarray, side: Support | Side, spec: Spec,
                 target_xy: Sequence[float] | np.ndarray = (0.0, 0.0)) -> np.ndarray:
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


def settled_swing_heights(goals: np.ndarray, side: Support | Side, spec: Spec) -> np.ndarray:
    """The lowest corner [m] (K,) of the other foot for poses standing on ``side``, after the servos' sag (the
    support leg's and the swing leg's own, :mod:`op2motion.model.compliance`); rigid where no equilibrium exists."""
    model, swing = Compliance(spec), SwingLegSag(spec, side)
    heights = []
    for start in range(0, len(goals), MATRIX_BELOW - 1):       # swarm-sized batches keep the chain frames
        points, frames = forward_dh_frames(servo_to_book(goals[start:start + MATRIX_BELOW - 1], side, spec), spec,
                                           full_com=True)
        first = ROW[f"{points.swing}_foot_0"]
        corners = points.data[first:first + 4]
        settled = model.settle(points, points.full())
        lowered = (model.settled_heights(points, settled, corners) + swing.heights(frames, corners)).min(axis=0)
        heights.append(np.where(np.isfinite(lowered), lowered, points.swing_foot_min_z))
    return np.concatenate(heights)


def _inside(xy: np.ndarray, side: Support | Side, spec: Spec) -> np.ndarray:
    """``xy`` [m] in the ``side`` sole's frame, moved to at least :data:`SHIFT_EDGE_M` inside its edges (to the
    middle between two edges closer together than twice that)."""
    front, back, left, right = spec.sole_extents(as_side(side))
    out = []
    for v, lo, hi in ((xy[0], -back + SHIFT_EDGE_M, front - SHIFT_EDGE_M), (xy[1], -right + SHIFT_EDGE_M,
                                                                           left - SHIFT_EDGE_M)):
        out.append((lo + hi) / 2.0 if lo > hi else float(np.clip(v, lo, hi)))
    return np.array(out)


def _folded(spec: Spec, servo: np.ndarray, side: Support | Side, fold: np.ndarray) -> np.ndarray:
    """Poses (N, 20): ``servo`` with the ``side`` leg folded by ``fold`` (N,) [rad] (the thigh turned forward by
    ``fold``, the shank back by twice that, the foot back by ``fold`` again, so the foot rises parallel to the sole
    it started from) and turned outward at the hip by :data:`LIFT_ABDUCT_RAD` (the foot kept parallel): the
    support leg sags inward under the load, and the swing leg must not come down onto it."""
    out = np.repeat(np.asarray(servo, dtype=float)[None], len(fold), axis=0)
    s = side[0]
    for joint, share in (("hip_pitch", -1.0), ("knee", 2.0), ("ank_pitch", -1.0)):
        out[:, spec.joint_names.index(f"{s}_{joint}")] += share * fold / spec.joint(f"{s}_{joint}").axis[1]
    outward = LIFT_ABDUCT_RAD * (1.0 if side == "left" else -1.0)      # about +X: the left leg swings to +Y
    out[:, spec.joint_names.index(f"{s}_hip_roll")] += outward / spec.joint(f"{s}_hip_roll").axis[0]
    out[:, spec.joint_names.index(f"{s}_ank_roll")] -= outward / spec.joint(f"{s}_ank_roll").axis[0]
    return out


def lift_swing(servo: np.ndarray, side: Support | Side, spec: Spec, clear_m: float = LIFT_CLEAR_M) -> np.ndarray:
    """A double-support pose ``servo`` (its weight already over the ``side`` foot) with the other leg folded until
    its foot's lowest corner, after the sag of standing on ``side`` alone, is ``clear_m`` [m] above the floor:
    the step that takes the load off a foot before the leg goes anywhere."""
    swing: Side = "right" if side == "left" else "left"
    folds = np.linspace(0.0, MAX_FOLD_RAD, 241)
    heights = settled_swing_heights(_folded(spec, servo, swing, folds), side, spec)
    clear = np.flatnonzero(heights >= clear_m)
    if clear.size == 0:
        raise CheckFailed(f"cannot lift the {swing} foot {clear_m * 1000:.0f} mm off the floor by folding "
                          f"the leg up to {np.degrees(MAX_FOLD_RAD):.0f}° at the hip")
    k = int(clear[0])
    fold = folds[k] if k == 0 else np.interp(clear_m, heights[k - 1:k + 1], folds[k - 1:k + 1])
    folded: np.ndarray = _folded(spec, servo, swing, np.array([fold]))[0]
    return folded


def with_weight_shifts(waypoints: Sequence[Waypoint], spec: Spec) -> tuple[list[Waypoint], list[str]]:
    """The sequence with a weight shift and a lift inserted between a double-support pose and a single-support
    one (either way round): the double-support pose leaned until its CoM is where the single-support pose has it
    (:func:`weight_shift`), then the other foot folded off the floor (:func:`lift_swing`); the reverse on the way
    down."""
    model = Compliance(spec)
    out, notes = [waypoints[0]], []
    for prev, nxt in zip(waypoints, waypoints[1:]):
        if prev.support.is_double != nxt.support.is_double:
            double, single = (prev, nxt) if prev.support.is_double else (nxt, prev)
            target = settled_com(single.servo, single.support, spec, model)
            if not np.all(np.isfinite(target)):
                raise CheckFailed(f"{single.name} cannot stand on the {single.support} foot: the servos would not "
                                  f"hold it")
            shifted = weight_shift(double.servo, single.support, spec, _inside(target, single.support, spec))
            lifted = lift_swing(shifted, single.support, spec)
            name = f"{double.name}@{single.support}"
            if prev.support.is_double:       # shift, lift, then move into the single-support pose
                out += [Waypoint(name, shifted, SHIFT_S, 0.0, Support.DOUBLE),
                        Waypoint(f"{name}+lift", lifted, LIFT_S, 0.0, single.support), nxt]
            else:                             # come down over the standing foot, put the foot down, shift back
                touch = lift_swing(shifted, single.support, spec, TOUCH_CLEAR_M)
                out += [Waypoint(f"{name}+lift", lifted, nxt.duration_s, 0.0, single.support),
                        Waypoint(f"{name}+touch", touch, LIFT_S, 0.0, single.support),
                        replace(nxt, duration_s=SHIFT_S + LIFT_S)]
            notes.append(f"inserted a {SHIFT_S:g} s weight shift onto the {single.support} foot and a {LIFT_S:g} s "
                         f"lift of the other ({'before' if prev.support.is_double else 'after'} {single.name})")
        else:
            out.append(nxt)
    return out, notes


def segment_side(a: Waypoint, b: Waypoint) -> Support | None:
    """The foot a segment stands on when one of its ends is a single-support pose (None for two feet)."""
    singles = [w.support for w in (a, b) if not w.support.is_double]
    if len(set(singles)) > 1:
        raise CheckFailed(f"{a.name} -> {b.name} goes from the {a.support} foot straight to the {b.support} foot: "
                          f"put a double-support pose between them")
    return singles[0] if singles else None


def balanced(goals: np.ndarray, segment: np.ndarray, waypoints: Sequence[Waypoint], spec: Spec) -> np.ndarray:
    """``goals`` (K, 20) [rad] with every segment that starts or ends on one foot kept in balance: each row is
    leaned at the ankles (both legs, as :func:`weight_shift` does) until its settled single-support CoM lies on
    the straight line between the settled CoMs of the segment's ends, at the row's progress along the segment
    (joint interpolation alone can carry the CoM far outside: from a stand to a one-leg reach it swings up to
    20 mm towards the toe edge on the way). The ends themselves are unchanged."""
    model = Compliance(spec)
    out = np.array(goals, dtype=float)
    for i, (a, b) in enumerate(zip(waypoints, waypoints[1:])):
        side = segment_side(a, b)
        rows = np.flatnonzero(segment == i)
        if side is None or rows.size == 0:
            continue
        ends = settled_coms(np.array([a.servo, b.servo]), side, spec, model)
        if not np.all(np.isfinite(ends)):
            raise CheckFailed(f"{a.name} -> {b.name}: the servos cannot hold an end of this segment on the {side} "
                              f"foot")
        span = b.servo - a.servo
        progress = np.clip((out[rows] - a.servo) @ span / max(float(span @ span), 1e-12), 0.0, 1.0)
        target = ends[0] + progress[:, None] * (ends[1] - ends[0])
        out[rows] = _lean_to(out[rows], side, target, spec, model, f"{a.name} -> {b.name}")
    return out


def _lean_to(rows: np.ndarray, side: Support | Side, target: np.ndarray, spec: Spec, model: Compliance,
             name: str) -> np.ndarray:
    """Rows (N, 20) leaned (Newton, batched) until their settled CoMs on ``side`` are at ``target`` (N, 2) [m]."""
    lean = np.zeros((len(rows), 2))

    def com(v: np.ndarray) -> np.ndarray:
        return settled_coms(_leaned(spec, rows, v[:, 0], v[:, 1]), side, spec, model)

    for _ in range(_ITERATIONS):
        now = com(lean)
        err = target - now
        if not np.all(np.isfinite(now)) or np.abs(lean).max() > MAX_LEAN_RAD:
            break
        if np.abs(err).max() < SHIFT_TOL_M:
            return _leaned(spec, rows, lean[:, 0], lean[:, 1])
        jac = np.stack([(com(lean + d) - now) / _STEP_RAD for d in np.eye(2) * _STEP_RAD], axis=2)   # (N, 2, 2)
        lean = lean + np.linalg.solve(jac, err[..., None])[..., 0]
    raise CheckFailed(f"{name}: cannot keep the centre of mass over the {side} foot along the way by leaning the "
                      f"legs (would need more than {np.degrees(MAX_LEAN_RAD):.0f}° or has no equilibrium)")
