"""The OP2 leg in closed form: sole pose in the torso frame <-> the six leg servo angles, batched over rows.

Each OP2 leg is hip yaw (about Z), hip roll (X) and hip pitch (Y) meeting in one point, the thigh (93 mm) to the
knee (Y), the calf (93 mm) to the ankle pitch (Y) and roll (X), which meet in one point 33.5 mm above the sole
(the framework's ``Kinematics.h``). The lengths, the hip positions and the axis signs are read from the spec, so
a robot with other links or mirrored servos gets its own IK.

The solution works in "natural" angles (positive about +Z, +X, +Y of the torso frame at servo zero) and maps them
to servo angles through each joint's axis sign. With the hip at the origin and the foot rotation ``R``, the hip
seen from the ankle in the foot frame, ``r = Rᵀ (hip - ankle)``, gives the knee from the law of cosines and the
ankle pitch and roll from the direction of ``r``; the hip's yaw, roll and pitch follow from
``Rz(yaw) Rx(roll) Ry(pitch) = R Rx(-ankle_roll) Ry(-knee - ankle_pitch)``. The knee bends forward (>= 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from op2motion.errors import InputError, ModelError
from op2motion.kinematics import small
from op2motion.robot.joints import LEG_JOINTS
from op2motion.robot.sides import Side
from op2motion.robot.spec import Spec

_AXES = (2, 0, 1, 1, 1, 0)          # the principal axis of each leg joint: Z, X, Y, Y, Y, X
REACH_TOL_M = 1e-9                  # a target this far beyond the straight leg still counts as reachable


@dataclass(frozen=True)
class Leg:
    """One leg's geometry from the spec: hip centre [m] in the torso frame, thigh and calf [m], ankle to sole [m],
    servo index and axis sign of each leg joint (natural angle x sign = servo angle)."""

    side: Side
    hip: np.ndarray
    thigh: float
    calf: float
    ankle_to_sole: float
    index: tuple[int, ...]
    sign: np.ndarray


def leg_of(spec: Spec, side: Side) -> Leg:
    """The ``side`` leg of the spec. Raises :class:`ModelError` if the leg is not the OP2's structure (principal
    axes, hip roll and pitch in one point, knee and ankle straight below)."""
    p = side[0]
    joints = [spec.joint(f"{p}_{n}") for n in LEG_JOINTS]
    signs = []
    for joint, axis in zip(joints, _AXES):
        a = np.asarray(joint.axis, dtype=float)
        others = np.delete(a, axis)
        if abs(abs(a[axis]) - 1.0) > 1e-9 or np.any(np.abs(others) > 1e-9) or any(joint.origin_rpy):
            raise ModelError(f"expected {joint.name} to turn about a principal axis with no origin rotation, got axis "
                             f"{joint.axis} and rpy {joint.origin_rpy}", "spec")
        signs.append(float(np.sign(a[axis])))
    yaw, roll, pitch, knee, ankle, ankle_roll = joints
    offsets = [np.asarray(j.origin_xyz, dtype=float) for j in joints]
    if (np.any(np.abs(offsets[1][:2]) > 1e-9) or np.any(np.abs(offsets[2]) > 1e-9) or np.any(np.abs(offsets[5]) > 1e-9)
            or np.any(np.abs(offsets[3][:2]) > 1e-9) or np.any(np.abs(offsets[4][:2]) > 1e-9)):
        raise ModelError(f"expected the {side} hip roll and pitch in one point and the knee and ankle straight below "
                         "the hip at servo zero", "spec")
    hip = offsets[0] + offsets[1]
    return Leg(side, hip, -offsets[3][2], -offsets[4][2], spec.foot.sole_below_ankle,
               tuple(spec.joint_names.index(j.name) for j in joints), np.array(signs))


def _rotation(a: np.ndarray | float, axis: int) -> np.ndarray:
    """Rotations (..., 3, 3) about coordinate ``axis`` (0 X, 1 Y, 2 Z) by ``a`` [rad] (filled in place: a scalar
    costs a few microseconds, not the tens that stacking nested lists did)."""
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a), np.sin(a)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    out = np.zeros(a.shape + (3, 3))
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    out[..., j, j] = c
    return out


def rot_x(a: np.ndarray | float) -> np.ndarray:
    """Rotations (..., 3, 3) about X by ``a`` [rad] (any shape, a float gives one (3, 3)); likewise
    :func:`rot_y`, :func:`rot_z`: the gait's one home for elementary rotations."""
    return _rotation(a, 0)


def rot_y(a: np.ndarray | float) -> np.ndarray:
    """Rotations (..., 3, 3) about Y by ``a`` [rad]."""
    return _rotation(a, 1)


def rot_z(a: np.ndarray | float) -> np.ndarray:
    """Rotations (..., 3, 3) about Z by ``a`` [rad]."""
    return _rotation(a, 2)


def leg_fk(leg: Leg, servo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sole centre (N, 3) [m] and sole rotation (N, 3, 3) in the torso frame for leg servo angles (N, 6) [rad]
    (the order of :data:`op2motion.robot.joints.LEG_JOINTS`)."""
    n = np.asarray(servo, dtype=float).reshape(-1, 6) * leg.sign
    yaw, roll, pitch, knee, ank, ank_roll = n.T
    hip_rot = rot_z(yaw) @ rot_x(roll) @ rot_y(pitch)
    down = np.array([0.0, 0.0, -1.0])
    knee_pos = leg.hip + hip_rot @ (down * leg.thigh)
    shin_rot = hip_rot @ rot_y(knee)
    ankle_pos = knee_pos + shin_rot @ (down * leg.calf)
    rot = shin_rot @ rot_y(ank) @ rot_x(ank_roll)
    return ankle_pos + rot @ (down * leg.ankle_to_sole), rot


def within_reach(leg: Leg, sole: np.ndarray, rot: np.ndarray, share: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Sole targets (N, 3) [m] pulled towards the hip along the hip–ankle line where they lie beyond ``share`` of
    the straight leg (a correction must never ask for more leg than there is); the rotations (N, 3, 3) unchanged."""
    sole = np.asarray(sole, dtype=float).reshape(-1, 3)
    rot = np.asarray(rot, dtype=float).reshape(-1, 3, 3)
    span = sole + rot @ np.array([0.0, 0.0, leg.ankle_to_sole]) - leg.hip
    reach = (leg.thigh + leg.calf) * share
    length = np.linalg.norm(span, axis=1)
    scale = np.where(length > reach, 1.0 - reach / np.maximum(length, 1e-12), 0.0)
    return sole - span * scale[:, None], rot


def leg_ik(leg: Leg, sole: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """Leg servo angles (N, 6) [rad] that put the sole centre at ``sole`` (N, 3) [m] with rotation ``rot``
    (N, 3, 3), both in the torso frame. Raises :class:`InputError` naming the first row beyond the leg's reach."""
    sole = np.asarray(sole, dtype=float).reshape(-1, 3)
    rot = np.asarray(rot, dtype=float).reshape(-1, 3, 3)
    ankle = sole + rot[:, :, 2] * leg.ankle_to_sole
    r = np.einsum("nji,nj->ni", rot, leg.hip - ankle)           # the hip seen from the ankle, foot frame
    c = np.sqrt((r * r).sum(axis=1))
    a, b = leg.thigh, leg.calf
    out_of_reach = (c > a + b + REACH_TOL_M) | (c < abs(a - b) + 1e-6)
    if np.any(out_of_reach):
        i = int(np.flatnonzero(out_of_reach)[0])
        raise InputError(f"expected the {leg.side} ankle within {a + b:.4f} m of the hip, got {c[i]:.4f} m at row "
                         f"{i}", "leg")
    hip_below = r[:, 2] <= 0.0
    if np.any(hip_below):
        below = int(np.flatnonzero(hip_below)[0])
        raise InputError(f"expected the {leg.side} hip above the ankle in the foot frame, got {r[below, 2]:.4f} m "
                         f"at row {below}", "leg")
    knee = np.arccos(np.minimum(np.maximum((c ** 2 - a ** 2 - b ** 2) / (2.0 * a * b), -1.0), 1.0))
    ank_roll = np.arctan2(r[:, 1], r[:, 2])
    # v: the hip from the ankle in the shin frame before the ankle pitch; its direction less r's gives the pitch
    vx, vz = -a * np.sin(knee), a * np.cos(knee) + b
    ank = np.arctan2(vx, vz) - np.arctan2(r[:, 0], np.hypot(r[:, 1], r[:, 2]))
    m = rot @ rot_x(-ank_roll) @ rot_y(-(knee + ank))
    out = np.empty((len(sole), 6))
    out[:, 0] = np.arctan2(-m[:, 0, 1], m[:, 1, 1])                                    # yaw
    out[:, 1] = np.arctan2(m[:, 2, 1], np.hypot(m[:, 2, 0], m[:, 2, 2]))               # roll
    out[:, 2] = np.arctan2(-m[:, 2, 0], m[:, 2, 2])                                    # pitch
    out[:, 3], out[:, 4], out[:, 5] = knee, ank, ank_roll
    servo: np.ndarray = out * leg.sign
    return servo


def within_reach_pose(leg: Leg, sole: Sequence[float], rot: Sequence[Sequence[float]], share: float = 1.0
                      ) -> small.Vec3:
    """:func:`within_reach` for one sole target (3,) [m] with rotation (3, 3) (tuples, lists: :mod:`.small`): the
    target, pulled in if need be (the per-tick path of a walk controller; the same arithmetic)."""
    foot = leg.ankle_to_sole
    hip = leg.hip.tolist()
    span = (sole[0] + rot[0][2] * foot - hip[0], sole[1] + rot[1][2] * foot - hip[1],
            sole[2] + rot[2][2] * foot - hip[2])
    reach = (leg.thigh + leg.calf) * share
    length = small.norm(span)
    scale = 1.0 - reach / max(length, 1e-12) if length > reach else 0.0
    return small.sub(sole, small.scaled(span, scale))


def leg_ik_pose(leg: Leg, sole: Sequence[float], rot: Sequence[Sequence[float]]) -> tuple[float, ...]:
    """:func:`leg_ik` for one sole pose: the six leg servo angles [rad] for the sole centre at ``sole`` (3,) [m]
    with rotation ``rot`` (3, 3) in the torso frame (tuples, lists: :mod:`.small`). The same arithmetic on floats:
    a walk controller solves two legs every 8 ms, and NumPy's call overhead made that a tenth of a walk check."""
    foot, (hx, hy, hz) = leg.ankle_to_sole, leg.hip.tolist()
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rot
    dx, dy, dz = hx - (sole[0] + r02 * foot), hy - (sole[1] + r12 * foot), hz - (sole[2] + r22 * foot)
    r = (r00 * dx + r10 * dy + r20 * dz, r01 * dx + r11 * dy + r21 * dz, r02 * dx + r12 * dy + r22 * dz)
    c = small.norm(r)
    a, b = leg.thigh, leg.calf
    if c > a + b + REACH_TOL_M or c < abs(a - b) + 1e-6:
        raise InputError(f"expected the {leg.side} ankle within {a + b:.4f} m of the hip, got {c:.4f} m at row 0",
                         "leg")
    if r[2] <= 0.0:
        raise InputError(f"expected the {leg.side} hip above the ankle in the foot frame, got {r[2]:.4f} m at row 0",
                         "leg")
    knee = math.acos(min(max((c ** 2 - a ** 2 - b ** 2) / (2.0 * a * b), -1.0), 1.0))
    ank_roll = math.atan2(r[1], r[2])
    ank = math.atan2(-a * math.sin(knee), a * math.cos(knee) + b) - math.atan2(r[0], math.hypot(r[1], r[2]))
    m = small.mul(small.mul(rot, small.rot_x(-ank_roll)), small.rot_y(-(knee + ank)))
    natural = (math.atan2(-m[0][1], m[1][1]), math.atan2(m[2][1], math.hypot(m[2][0], m[2][2])),
               math.atan2(-m[2][0], m[2][2]), knee, ank, ank_roll)
    sign = leg.sign.tolist()
    return tuple([natural[i] * sign[i] for i in range(6)])
