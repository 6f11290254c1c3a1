"""The posture cost of a whole swarm in one compiled loop (numba, cached on disk): the PSO's hot path.

It computes what :class:`~op2motion.posture.cost.CostModel` computes for the D-H model (chain frames, body points,
the full-inertia CoM settled on compliant servos or the book's lumped CoM, the swing foot's sag, stability margin,
torso tilt, self-clearance) pose by pose, with no NumPy call per term: a swarm of 50 costs about as much as the
arithmetic. The constants come from :func:`.kernel_plan.kernel_plan`, read off the same plans the NumPy model uses;
tests compare every term of both on random swarms. Self-clearance is searched exactly only below the penalty's
threshold (a pair whose bounding spheres are farther apart reports that lower bound), which gives the same cost.

The collision geometry (segments, boxes, the least clearance of a pose) is in :mod:`.kernel_geometry`. Importing
this module imports numba (about 0.15 s); the first call in a fresh install compiles the loop (a few
seconds, then cached beside the module or in numba's user cache).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from op2motion.errors import ModelError
from op2motion.posture.jit import njit_cached
from op2motion.posture.kernel_geometry import clearance_of, mul
from op2motion.posture.kernel_plan import KernelPlan
from op2motion.processes.compiled import CompileOnce

TERMS = ("total", "book", "hand_error", "margin", "swing_min_z", "tilt", "collision", "sag_tilt", "clearance",
         "swing_lift")

(_T_TOTAL, _T_BOOK, _T_HAND_ERROR, _T_MARGIN, _T_SWING_MIN_Z, _T_TILT, _T_COLLISION, _T_SAG_TILT, _T_CLEARANCE,
 _T_SWING_LIFT) = range(len(TERMS))                  # the columns, as compile-time integers
TOTAL, HAND_ERROR = _T_TOTAL, _T_HAND_ERROR
_C_PENALTY, _C_VIOL, _C_MARGIN, _C_CAP, _C_UPRIGHT, _C_SAG, _C_CLEAR, _C_LIFTED, _C_FLOOR, _C_G = range(10)


@njit_cached
def _solve(m: np.ndarray, rhs: np.ndarray, n: int, out: np.ndarray) -> float:
    """Solve the leading n x n system in place (Gaussian elimination, partial pivoting) into ``out``; return its
    determinant."""
    det = 1.0
    for col in range(n):
        pivot = col
        for r in range(col + 1, n):
            if abs(m[r, col]) > abs(m[pivot, col]):
                pivot = r
        if m[pivot, col] == 0.0:
            return 0.0
        if pivot != col:
            det = -det
            for c in range(n):
                m[col, c], m[pivot, c] = m[pivot, c], m[col, c]
            rhs[col], rhs[pivot] = rhs[pivot], rhs[col]
        det *= m[col, col]
        for r in range(col + 1, n):
            factor = m[r, col] / m[col, col]
            for c in range(col, n):
                m[r, c] -= factor * m[col, c]
            rhs[r] -= factor * rhs[col]
    for r in range(n - 1, -1, -1):
        acc = rhs[r]
        for c in range(r + 1, n):
            acc -= m[r, c] * out[c]
        out[r] = acc / m[r, r]
    return det


@njit_cached
def _swarm(q: np.ndarray, only_below: np.ndarray, plan: KernelPlan, within: float, out: np.ndarray,
           body_pts: np.ndarray, body_com: np.ndarray) -> None:
    """Every cost term of poses ``q`` (N, 20) [rad] into ``out`` (N, len(TERMS)), clearances exact below
    ``within`` [m]; see :func:`swarm_terms`. Where ``body_pts`` (N, R, 3) and ``body_com`` (N, 3) have rows (else
    (0, ...)), each pose's body points and full-inertia CoM [m] too (:func:`body_features`).

    One loop on purpose: with every array local, LLVM keeps the small systems in registers (split into helpers
    that share scratch arrays, the same arithmetic ran 2.5 times slower)."""
    (parent, slot_joint, slot_fixed, var, sign, offset, basis, fixed_local, root, row_slot, row_point, const_rows,
     pelvis, lumped, com_slots, com_mass, com_weighted, total_mass, ch_rows, ch_size, ch_s0, ch_sz, ch_rx,
     ch_axis_rows, sw_slots, sw_local, sw_axes, sw_kp, sw_link_slots, sw_link_com, sw_link_mass, _, _, _, _, _, _,
     _, _, hand_row, ankle_row, swing_first, torso_rows, torso_ab, target, extents, full, consts, _, _, _, _) = plan
    u, legs = ch_s0.shape[1], sw_slots.shape[0]
    frames, local, pts = np.empty((parent.shape[0], 4, 4)), np.empty((4, 4)), np.empty((row_slot.shape[0], 3))
    system, rhs, sol, thetas = np.empty((u, u)), np.empty(u), np.empty(u), np.zeros((2, u))
    joint, origin, axis, theta = np.empty((4, 4)), np.empty((legs, 3)), np.empty((legs, 3)), np.empty(legs)
    link_c, com, settled, sag = np.empty((legs, 3)), np.empty(3), np.empty(2), np.empty(2)
    shape_w = np.empty((plan.sh_slots.shape[0], 4, 4))
    top = ch_rx.shape[1] - 1                                   # where the CoM's coefficients sit
    flat = local.reshape(16)
    for i in range(q.shape[0]):
        frames[0] = root                                       # the D-H chain, parents before children
        for s in range(1, parent.shape[0]):
            j = slot_joint[s]
            if j >= 0:
                delta = sign[j] * q[i, var[j]] + offset[j]
                c, sn = math.cos(delta), math.sin(delta)
                for e in range(16):
                    flat[e] = c * basis[j, 0, e] + sn * basis[j, 1, e] + basis[j, 2, e]
                mul(frames[parent[s]], local, frames[s])
            else:
                mul(frames[parent[s]], fixed_local[slot_fixed[s]], frames[s])
        for r in range(row_slot.shape[0]):                     # body points
            s = row_slot[r]
            for k in range(3):
                if s >= 0:
                    pts[r, k] = (frames[s, k, 0] * row_point[r, 0] + frames[s, k, 1] * row_point[r, 1]
                                 + frames[s, k, 2] * row_point[r, 2] + frames[s, k, 3])
                elif s == -1:
                    pts[r, k] = const_rows[r, k]
                else:                                          # the pelvis: the hips' midpoint
                    pts[r, k] = 0.5 * (frames[pelvis[1], k, 3] + frames[pelvis[2], k, 3])
        if body_pts.shape[0] > 0:
            body_pts[i] = pts
        sq = 0.0
        for k in range(3):
            sq += (pts[hand_row, k] - target[k]) * (pts[hand_row, k] - target[k])
        hand_error = math.sqrt(sq)
        f = swing_first
        swing_min_z = min(min(pts[f, 2], pts[f + 1, 2]), min(pts[f + 2, 2], pts[f + 3, 2]))
        com_x, com_y, sag_tilt = 0.0, 0.0, 0.0
        if full:                                               # the body physics simulates: full inertia
            com[:] = 0.0                                       # sum of R (M c) + M o over the link inertials
            for m in range(com_slots.shape[0]):
                for k in range(3):
                    com[k] += (frames[com_slots[m], k, 0] * com_weighted[m, 0]
                               + frames[com_slots[m], k, 1] * com_weighted[m, 1]
                               + frames[com_slots[m], k, 2] * com_weighted[m, 2]
                               + com_mass[m] * frames[com_slots[m], k, 3])
            for k in range(3):
                com[k] /= total_mass
            if body_com.shape[0] > 0:
                body_com[i] = com
            settled_ok = True                                  # the compliance systems, pitch in x, roll in y
            for ch in range(2):
                n = ch_size[ch]
                for a in range(n):
                    rhs[a] = com[ch] * ch_rx[ch, top, a]
                    for b in range(n):
                        system[a, b] = ch_s0[ch, a, b] + com[2] * ch_sz[ch, top, a, b]
                for t in range(ch_rows.shape[1]):
                    r = ch_rows[ch, t]
                    if r >= 0:
                        for a in range(n):
                            rhs[a] += pts[r, ch] * ch_rx[ch, t, a]
                            for b in range(n):
                                system[a, b] += pts[r, 2] * ch_sz[ch, t, a, b]
                if _solve(system, rhs, n, sol) > 0.0:          # the servos outweigh gravity's negative stiffness
                    settled[ch], sag[ch] = sol[0] / total_mass, 0.0
                    for a in range(1, n):
                        thetas[ch, a - 1] = sol[a]
                        sag[ch] += sol[a]
                else:
                    settled_ok = False
                    settled[ch] = math.copysign(np.inf, com[ch] - pts[ankle_row, ch])
                    sag[ch] = np.inf
            com_x, com_y, sag_tilt = settled[0], settled[1], math.hypot(sag[0], sag[1])
            lowest = swing_min_z
            if settled_ok:                                     # the swing leg hangs on its springs
                for leg in range(legs):
                    mul(frames[sw_slots[leg]], sw_local[leg], joint)
                    for k in range(3):
                        origin[leg, k] = joint[k, 3]
                        axis[leg, k] = (joint[k, 0] * sw_axes[leg, 0] + joint[k, 1] * sw_axes[leg, 1]
                                        + joint[k, 2] * sw_axes[leg, 2])
                        lf = sw_link_slots[leg]
                        link_c[leg, k] = (frames[lf, k, 0] * sw_link_com[leg, 0] + frames[lf, k, 1] * sw_link_com[
                            leg, 1] + frames[lf, k, 2] * sw_link_com[leg, 2] + frames[lf, k, 3])
                mass, mx, my = 0.0, 0.0, 0.0
                for leg in range(legs - 1, -1, -1):            # links j..end: their mass and moment
                    mass += sw_link_mass[leg]
                    mx += sw_link_mass[leg] * link_c[leg, 0]
                    my += sw_link_mass[leg] * link_c[leg, 1]
                    lever_x, lever_y = mx - mass * origin[leg, 0], my - mass * origin[leg, 1]
                    theta[leg] = -consts[_C_G] * (axis[leg, 0] * lever_y - axis[leg, 1] * lever_x) / sw_kp[leg]
                lowest = np.inf
                for corner in range(swing_first, swing_first + 4):
                    z = pts[corner, 2]
                    for ch in range(2):
                        for a in range(ch_size[ch] - 1):
                            z -= thetas[ch, a] * (pts[corner, ch] - pts[ch_axis_rows[ch, a], ch])
                    for leg in range(legs):
                        rel_x, rel_y = pts[corner, 0] - origin[leg, 0], pts[corner, 1] - origin[leg, 1]
                        z += theta[leg] * (axis[leg, 0] * rel_y - axis[leg, 1] * rel_x)
                    lowest = min(lowest, z)
            lift = lowest - consts[_C_LIFTED]
        else:                                                  # the book's lumped masses on rigid joints
            for r in range(row_slot.shape[0]):
                com_x += lumped[r] * pts[r, 0]
                com_y += lumped[r] * pts[r, 1]
            lift = swing_min_z + consts[_C_FLOOR]
        margin = _margin(com_x, com_y, extents)
        sag_excess = max(min(sag_tilt, 1.0) - consts[_C_SAG], 0.0)
        book = hand_error + (consts[_C_PENALTY] if lift < 0.0 else 0.0) + (
            consts[_C_PENALTY] if margin < 0.0 or sag_excess > 0.0 else 0.0)
        slope = consts[_C_VIOL] * (max(-lift, 0.0) + min(max(-margin, 0.0), 1.0) + 0.1 * sag_excess)
        tilt = _torso_tilt(pts, torso_rows, torso_ab)
        total = (book + slope + consts[_C_MARGIN] * (consts[_C_CAP] - min(margin, consts[_C_CAP]))
                 + consts[_C_UPRIGHT] * tilt * tilt)
        collision, clearance = 0.0, np.nan
        if total < only_below[i]:
            clearance = clearance_of(frames, plan, within, shape_w)
            deficit = max(consts[_C_CLEAR] - clearance, 0.0)
            collision = (consts[_C_PENALTY] if deficit > 0.0 else 0.0) + consts[_C_VIOL] * deficit
        out[i, _T_TOTAL], out[i, _T_BOOK], out[i, _T_HAND_ERROR], out[i, _T_MARGIN] = (
            total + collision, book, hand_error, margin)
        out[i, _T_SWING_MIN_Z], out[i, _T_TILT], out[i, _T_COLLISION], out[i, _T_SAG_TILT] = (
            swing_min_z, tilt, collision, sag_tilt)
        out[i, _T_CLEARANCE], out[i, _T_SWING_LIFT] = clearance, lift


@njit_cached
def _margin(x: float, y: float, extents: np.ndarray) -> float:
    """:func:`op2motion.robot.balance.rectangle_margin` of one point [m]."""
    front, back, left, right = extents[0], extents[1], extents[2], extents[3]
    inside: float = min(min(front - x, x + back), min(left - y, y + right))
    if inside >= 0.0:
        return inside
    return -math.hypot(max(max(x - front, -back - x), 0.0), max(max(y - left, -right - y), 0.0))


@njit_cached
def _torso_tilt(pts: np.ndarray, rows: np.ndarray, ab: np.ndarray) -> float:
    """:func:`op2motion.posture.cost.torso_tilt` of one pose [rad] (``rows``: neck, pelvis, shoulders)."""
    neck, pelvis, lsho, rsho = rows[0], rows[1], rows[2], rows[3]
    y0, y1, y2 = pts[lsho, 0] - pts[rsho, 0], pts[lsho, 1] - pts[rsho, 1], pts[lsho, 2] - pts[rsho, 2]
    u0, u1, u2 = pts[pelvis, 0] - pts[neck, 0], pts[pelvis, 1] - pts[neck, 1], pts[pelvis, 2] - pts[neck, 2]
    ny, nu = math.sqrt(y0 * y0 + y1 * y1 + y2 * y2), math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    w_z = (y0 / ny) * (u1 / nu) - (y1 / ny) * (u0 / nu)
    return math.acos(min(max(ab[1] * (u2 / nu) - ab[0] * w_z, -1.0), 1.0))


#: The loop, compiled by one process at a time on a fresh install (:mod:`op2motion.processes.compiled`).
_SWARM: CompileOnce[None] = CompileOnce(_swarm)


def swarm_terms(plan: KernelPlan, q: np.ndarray, only_below: np.ndarray | None = None,
                exact_below_m: float | None = None) -> np.ndarray:
    """Every cost term (columns :data:`TERMS`) of poses ``q`` (N, 20) [rad, book variables], (N, len(TERMS)).

    The self-clearance of pose i is searched only where its other terms cost less than ``only_below[i]`` (a PSO
    particle that cannot beat its personal best): elsewhere its clearance is NaN and its collision penalty 0, as
    :class:`~op2motion.posture.cost.CostModel` reports them. Clearances are exact below ``exact_below_m`` [m]
    (default: the penalty's threshold, all the cost needs) and lower bounds above it."""
    q = np.ascontiguousarray(q, dtype=float)
    limit = np.full(q.shape[0], np.inf) if only_below is None else np.ascontiguousarray(only_below, dtype=float)
    out = np.empty((q.shape[0], len(TERMS)))
    within = plan.consts[_C_CLEAR] if exact_below_m is None else float(exact_below_m)
    _SWARM(q, limit, plan, within, out, np.empty((0, plan.row_slot.shape[0], 3)), np.empty((0, 3)))
    return out


@dataclass(frozen=True)
class BodyFeatures:
    """Poses' body ``points`` (N, R, 3) [m] (rows as :mod:`op2motion.kinematics.points`), full-inertia ``com``
    (N, 3) [m] and least self-``clearance`` (N,) [m]."""

    points: np.ndarray
    com: np.ndarray
    clearance: np.ndarray


def body_features(plan: KernelPlan, q: np.ndarray, within_m: float) -> BodyFeatures:
    """Body points (N, R, 3) [m] (rows as :mod:`op2motion.kinematics.points`), full-inertia CoM (N, 3) [m] and least
    self-clearance (N,) [m] (exact below ``within_m``, a lower bound above it) of poses ``q`` (N, 20) [rad, book
    variables] in the frame of ``plan``'s support sole (a plan of the full-inertia body): the numbers of
    :func:`op2motion.kinematics.forward` on the D-H model and the cost model's clearance, from the same loop (the
    whole-body IK asks for a few poses at a time, thousands of times a line)."""
    q = np.ascontiguousarray(q, dtype=float)
    if not plan.full:
        raise ModelError("expected a plan of the full-inertia body for its CoM", "plan")
    out = np.empty((q.shape[0], len(TERMS)))
    pts, com = np.empty((q.shape[0], plan.row_slot.shape[0], 3)), np.empty((q.shape[0], 3))
    _SWARM(q, np.full(q.shape[0], np.inf), plan, float(within_m), out, pts, com)
    return BodyFeatures(pts, com, out[:, _T_CLEARANCE])
