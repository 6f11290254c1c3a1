"""The compiled body of a batch of poses (numba, cached on disk): for each pose its D-H chain, body points,
full-inertia CoM and least self-clearance, in one loop. :func:`body_features` gives the whole-body IK
(:mod:`op2motion.motion.whole_body`) the numbers of :func:`op2motion.kinematics.forward` on the D-H model and of the
cost model's clearance without a NumPy call per term (it asks for a few poses at a time, thousands of times a line;
a test holds both to the same numbers). The PSO's loop (:mod:`.kernel`) does the same arithmetic inline: calling
these helpers from it cost the PSO 9 % (``pso_solve_ms`` 36.8 -> 40.2 ms), so it keeps its own copy, held to the
same NumPy model by its own test."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from op2motion.posture.kernel_geometry import clearance_of, mul
from op2motion.posture.kernel_plan import KernelPlan


@njit(cache=True, error_model="numpy")
def chain(q: np.ndarray, i: int, plan: KernelPlan, frames: np.ndarray, local: np.ndarray, flat: np.ndarray) -> None:
    """The D-H chain's frames (S, 4, 4) of pose ``i`` of ``q`` (N, 20) (book variables) [rad, m], parents before
    children (``local`` (4, 4): scratch, ``flat`` its (16,) view)."""
    parent, slot_joint, slot_fixed, var, sign, offset, basis = (plan.parent, plan.slot_joint, plan.slot_fixed,
                                                                 plan.var, plan.sign, plan.offset, plan.basis)
    frames[0] = plan.root
    for s in range(1, parent.shape[0]):
        j = slot_joint[s]
        if j >= 0:
            delta = sign[j] * q[i, var[j]] + offset[j]
            c, sn = math.cos(delta), math.sin(delta)
            for e in range(16):
                flat[e] = c * basis[j, 0, e] + sn * basis[j, 1, e] + basis[j, 2, e]
            mul(frames[parent[s]], local, frames[s])
        else:
            mul(frames[parent[s]], plan.fixed_local[slot_fixed[s]], frames[s])


@njit(cache=True, error_model="numpy")
def points(frames: np.ndarray, plan: KernelPlan, pts: np.ndarray) -> None:
    """The body points (R, 3) [m] of one pose's chain ``frames``."""
    row_slot, row_point, const_rows, pelvis = plan.row_slot, plan.row_point, plan.const_rows, plan.pelvis
    for r in range(row_slot.shape[0]):
        s = row_slot[r]
        for k in range(3):
            if s >= 0:
                pts[r, k] = (frames[s, k, 0] * row_point[r, 0] + frames[s, k, 1] * row_point[r, 1]
                             + frames[s, k, 2] * row_point[r, 2] + frames[s, k, 3])
            elif s == -1:
                pts[r, k] = const_rows[r, k]
            else:                                          # the pelvis: the hips' midpoint
                pts[r, k] = 0.5 * (frames[pelvis[1], k, 3] + frames[pelvis[2], k, 3])


@njit(cache=True, error_model="numpy")
def full_com(frames: np.ndarray, plan: KernelPlan, com: np.ndarray) -> None:
    """The full-inertia CoM (3,) [m] of one pose's chain ``frames``: the sum of R (M c) + M o over the link
    inertials, over the total mass."""
    com_slots, com_weighted, com_mass = plan.com_slots, plan.com_weighted, plan.com_mass
    com[:] = 0.0
    for m in range(com_slots.shape[0]):
        for k in range(3):
            com[k] += (frames[com_slots[m], k, 0] * com_weighted[m, 0]
                       + frames[com_slots[m], k, 1] * com_weighted[m, 1]
                       + frames[com_slots[m], k, 2] * com_weighted[m, 2]
                       + com_mass[m] * frames[com_slots[m], k, 3])
    for k in range(3):
        com[k] /= plan.total_mass


@njit(cache=True, error_model="numpy")
def _bodies(q: np.ndarray, plan: KernelPlan, within: float, pts: np.ndarray, com: np.ndarray,
            clearance: np.ndarray) -> None:
    frames, local = np.empty((plan.parent.shape[0], 4, 4)), np.empty((4, 4))
    flat = local.reshape(16)
    shape_w = np.empty((plan.sh_slots.shape[0], 4, 4))
    for i in range(q.shape[0]):
        chain(q, i, plan, frames, local, flat)
        points(frames, plan, pts[i])
        full_com(frames, plan, com[i])
        clearance[i] = clearance_of(frames, plan, within, shape_w)


def body_features(plan: KernelPlan, q: np.ndarray, within_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body points (N, R, 3) [m] (rows as :mod:`op2motion.kinematics.points`), full-inertia CoM (N, 3) [m] and least
    self-clearance (N,) [m] (exact below ``within_m``, a lower bound above it) of poses ``q`` (N, 20) [rad, book
    variables], in the frame of ``plan``'s support sole."""
    q = np.ascontiguousarray(q, dtype=float)
    pts = np.empty((q.shape[0], plan.row_slot.shape[0], 3))
    com, clearance = np.empty((q.shape[0], 3)), np.empty(q.shape[0])
    _bodies(q, plan, float(within_m), pts, com, clearance)
    return pts, com, clearance
