"""The whole-body IK's poses in one compiled loop (numba, cached on disk): unknowns (torso shift and turn, arm) to
servo angles, the legs by the closed-form leg IK (the arithmetic of :func:`op2motion.kinematics.leg_ik.leg_ik` and
:func:`~op2motion.kinematics.leg_ik.within_reach`, pose by pose; a test holds both to the same numbers). The IK asks
for a few poses at a time, thousands of times a line: in NumPy each ask cost some fifty array calls. The first
call after an install compiles it (about 4 s, then cached beside the module); 3 x 3 products are written out
(NumPy's ``@`` on them compiled for 7 s)."""

from __future__ import annotations

import math

import numpy as np

from op2motion.posture.jit import njit_cached
from op2motion.processes.compiled import CompileOnce

OK, OUT_OF_REACH, HIP_BELOW = 0, 1, 2      # what a leg's IK found


@njit_cached
def _mul(a: np.ndarray, b: np.ndarray, out: np.ndarray, a_transposed: bool = False) -> None:
    """out = a @ b (or a.T @ b) for 3 x 3 matrices (no BLAS call: it compiled slowly for matrices this small)."""
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc += (a[k, i] if a_transposed else a[i, k]) * b[k, j]
            out[i, j] = acc


@njit_cached
def _rodrigues(v: np.ndarray, out: np.ndarray) -> None:
    """The rotation matrix (3, 3) of a rotation vector (3,) [rad]: I + sin(a) K + (1 - cos(a)) K²."""
    angle = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    d = max(angle, 1e-12)
    x, y, z = v[0] / d, v[1] / d, v[2] / d
    s, c1 = math.sin(angle), 1.0 - math.cos(angle)
    k = ((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0))
    for i in range(3):
        for j in range(3):
            kk = k[i][0] * k[0][j] + k[i][1] * k[1][j] + k[i][2] * k[2][j]
            out[i, j] = (1.0 if i == j else 0.0) + s * k[i][j] + c1 * kk


@njit_cached
def _leg(hip: np.ndarray, lengths: np.ndarray, sole: np.ndarray, rot: np.ndarray, share: float,
         out: np.ndarray) -> int:
    """Leg servo angles (6,) [rad, before the leg's signs] for the sole at ``sole`` (3,) [m] turned ``rot``
    (3, 3) in the torso frame, pulled in to ``share`` of the straight leg first; ``lengths``: thigh, calf, ankle to
    sole [m]. Returns :data:`OK` or why not."""
    a, b, foot = lengths[0], lengths[1], lengths[2]
    span = np.empty(3)
    for k in range(3):
        span[k] = sole[k] + rot[k, 2] * foot - hip[k]
    length = math.sqrt(span[0] * span[0] + span[1] * span[1] + span[2] * span[2])
    reach = (a + b) * share
    scale = 1.0 - reach / max(length, 1e-12) if length > reach else 0.0
    r = np.zeros(3)                                   # the hip seen from the ankle, foot frame
    for k in range(3):
        d = hip[k] - (sole[k] - span[k] * scale + rot[k, 2] * foot)
        for i in range(3):
            r[i] += rot[k, i] * d
    c = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    if c > a + b + 1e-9 or c < abs(a - b) + 1e-6:
        return OUT_OF_REACH
    if r[2] <= 0.0:
        return HIP_BELOW
    knee = math.acos(min(max((c * c - a * a - b * b) / (2.0 * a * b), -1.0), 1.0))
    ank_roll = math.atan2(r[1], r[2])
    ank = math.atan2(-a * math.sin(knee), a * math.cos(knee) + b) - math.atan2(r[0], math.hypot(r[1], r[2]))
    cr, sr = math.cos(-ank_roll), math.sin(-ank_roll)
    cp, sp = math.cos(-(knee + ank)), math.sin(-(knee + ank))
    turn = np.empty((3, 3))                           # rot_x(-ank_roll) @ rot_y(-(knee + ank))
    turn[0, 0], turn[0, 1], turn[0, 2] = cp, 0.0, sp
    turn[1, 0], turn[1, 1], turn[1, 2] = -sr * -sp, cr, -sr * cp
    turn[2, 0], turn[2, 1], turn[2, 2] = cr * -sp, sr, cr * cp
    m = np.empty((3, 3))
    _mul(rot, turn, m)
    out[0] = math.atan2(-m[0, 1], m[1, 1])
    out[1] = math.atan2(m[2, 1], math.hypot(m[2, 0], m[2, 2]))
    out[2] = math.atan2(-m[2, 0], m[2, 2])
    out[3], out[4], out[5] = knee, ank, ank_roll
    return OK


@njit_cached
def _servo_rows(x: np.ndarray, body: tuple[np.ndarray, ...], legs: tuple[np.ndarray, ...],
                limits: tuple[np.ndarray, ...], out: np.ndarray) -> int:
    """Poses ``out`` (N, 20) [rad] of unknowns ``x`` (N, 9): the torso shift [m] and rotation vector [rad] from
    ``body`` = (torso rotation (3, 3), torso position (3,) in the stance sole's frame, the start pose (20,), the arm
    joints' indices (3,)), the other joints from the start; each leg l of ``legs`` = (hips (L, 3), thigh, calf and
    foot lengths (L, 3), signs (L, 6), servo indices (L, 6), soles (L, 3) and their rotations (L, 3, 3) [world],
    reach shares (L,)) putting its sole where it is; the joints of ``limits`` = (indices, lower, upper) clipped.
    Returns -1, or ``leg * 3 + why`` for the first leg that could not."""
    torso_rot, torso_pos, start, arm = body
    hips, lengths, signs, index, soles, sole_rots, shares = legs
    moved, lower, upper = limits
    turn, rot, local_rot, angles = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty(6)
    local = np.empty(3)
    for n in range(x.shape[0]):
        _rodrigues(x[n, 3:6], turn)
        _mul(turn, torso_rot, rot)                    # the torso in the world
        out[n, :] = start
        for k in range(3):
            out[n, arm[k]] = x[n, 6 + k]
        for leg in range(hips.shape[0]):
            for i in range(3):                        # the sole in the torso frame
                local[i] = 0.0
                for k in range(3):
                    local[i] += rot[k, i] * (soles[leg, k] - torso_pos[k] - x[n, k])
            _mul(rot, sole_rots[leg], local_rot, True)
            why = _leg(hips[leg], lengths[leg], local, local_rot, shares[leg], angles)
            if why != OK:
                return leg * 3 + why
            for k in range(6):
                out[n, index[leg, k]] = angles[k] * signs[leg, k]
        for k in range(moved.shape[0]):
            out[n, moved[k]] = min(max(out[n, moved[k]], lower[k]), upper[k])
    return -1


#: :func:`_servo_rows`, compiled by one process at a time on a fresh install (:mod:`op2motion.processes.compiled`).
servo_rows: CompileOnce[int] = CompileOnce(_servo_rows)
