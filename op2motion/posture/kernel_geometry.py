"""The compiled kernel's geometry (numba, cached on disk): rigid transforms, and the least clearance between a
pose's collision shapes, exactly as :mod:`op2motion.kinematics.shapes` computes it (a swept segment against a box by
sampling its convex distance in rounds, box against box by each one's twelve edges, capsules in closed form), with two
cheap lower bounds first (bounding spheres; a box's corners' bounding box in the other's frame): a pair whose lower
bound is at least ``within`` reports that bound. Used by :mod:`.kernel`.
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.posture.jit import njit_cached
from op2motion.posture.kernel_plan import KernelPlan


@njit_cached
def mul(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """out = a @ b for 4x4 rigid transforms (bottom rows 0 0 0 1, which stay as they are)."""
    for r in range(3):
        a0, a1, a2 = a[r, 0], a[r, 1], a[r, 2]
        for c in range(3):
            out[r, c] = a0 * b[0, c] + a1 * b[1, c] + a2 * b[2, c]
        out[r, 3] = a0 * b[0, 3] + a1 * b[1, 3] + a2 * b[2, 3] + a[r, 3]
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0


@njit_cached
def _box_distance(x: float, y: float, z: float, half: np.ndarray) -> float:
    """Signed distance [m] of a point in a box's frame to the box of half extents ``half``."""
    qx, qy, qz = abs(x) - half[0], abs(y) - half[1], abs(z) - half[2]
    inside: float = min(max(max(qx, qy), qz), 0.0)
    ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
    return math.sqrt(ox * ox + oy * oy + oz * oz) + inside


@njit_cached
def _segment_box(a: np.ndarray, b: np.ndarray, half: np.ndarray, rim: float, within: float, grid: np.ndarray,
                 rounds: int) -> float:
    """Clearance [m] of a segment a-b swept by ``rim`` to a box (both in the box frame): the segment's bounding box
    first, then (below ``within``) the sampled search of :func:`op2motion.kinematics.shapes._segment_box`."""
    sq = 0.0
    for k in range(3):
        o = max(max(min(a[k], b[k]) - half[k], -half[k] - max(a[k], b[k])), 0.0)
        sq += o * o
    value = math.sqrt(sq) - rim
    if value >= within:
        return value
    d0, d1, d2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    lo, width, best = 0.0, 1.0, np.inf
    samples = grid.shape[0]
    for _ in range(rounds):
        i_best, f_best = 0, np.inf
        for i in range(samples):
            t = lo + width * grid[i]
            f = _box_distance(a[0] + t * d0, a[1] + t * d1, a[2] + t * d2, half)
            if f < f_best:
                i_best, f_best = i, f
        best = min(best, f_best)
        step = width / (samples - 1)
        lo = min(max(lo + (i_best - 1) * step, 0.0), 1.0 - 2.0 * step)
        width = 2.0 * step
    return best - rim


@njit_cached
def _segment_segment(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> float:
    """Distance [m] between segments p1-q1 and p2-q2 (as :func:`op2motion.kinematics.shapes._segment_segment`)."""
    tiny = 1e-15
    a = e = b = c = f = 0.0
    for k in range(3):
        d1, d2, r = q1[k] - p1[k], q2[k] - p2[k], p1[k] - p2[k]
        a += d1 * d1
        e += d2 * d2
        b += d1 * d2
        c += d1 * r
        f += d2 * r
    denom = a * e - b * b
    s = min(max((b * f - c * e) / max(denom, tiny), 0.0), 1.0) if denom > tiny else 0.0
    t = (b * s + f) / max(e, tiny) if e > tiny else 0.0
    if t < 0.0:
        s = min(max(-c / max(a, tiny), 0.0), 1.0) if a > tiny else 0.0
    elif t > 1.0:
        s = min(max((b - c) / max(a, tiny), 0.0), 1.0) if a > tiny else 0.0
    t = min(max(t, 0.0), 1.0)
    sq = 0.0
    for k in range(3):
        g = (p1[k] + s * (q1[k] - p1[k])) - (p2[k] + t * (q2[k] - p2[k]))
        sq += g * g
    return math.sqrt(sq)


@njit_cached
def _into(world: np.ndarray, box: np.ndarray, out: np.ndarray) -> None:
    """A world point into a shape's frame (4, 4): out = R^T (world - o)."""
    for k in range(3):
        out[k] = ((world[0] - box[0, 3]) * box[0, k] + (world[1] - box[1, 3]) * box[1, k]
                  + (world[2] - box[2, 3]) * box[2, k])


@njit_cached
def clearance_of(frames: np.ndarray, plan: KernelPlan, within: float, shape_w: np.ndarray) -> float:
    """The least clearance [m] between the collision shapes of one pose (chain ``frames``; ``shape_w`` (H, 4, 4)
    receives the shapes' frames): exact below ``within``, a lower bound above it."""
    corners, ends, a, b = np.empty((8, 3)), np.empty((4, 3)), np.empty(3), np.empty(3)
    sh_slots, sh_local = plan.sh_slots, plan.sh_local
    pairs, sh_bound, sh_box, sh_half = plan.pairs, plan.sh_bound, plan.sh_box, plan.sh_half
    for h in range(sh_slots.shape[0]):
        mul(frames[sh_slots[h]], sh_local[h], shape_w[h])
    best = np.inf
    for p in range(pairs.shape[0]):
        i, j = pairs[p, 0], pairs[p, 1]
        wi, wj = shape_w[i], shape_w[j]
        gx, gy, gz = wi[0, 3] - wj[0, 3], wi[1, 3] - wj[1, 3], wi[2, 3] - wj[2, 3]
        value = math.sqrt(gx * gx + gy * gy + gz * gz) - (sh_bound[i] + sh_bound[j])
        if value < within:
            if sh_box[i] and sh_box[j]:
                value = min(_box_box(shape_w[i], shape_w[j], sh_half[i], sh_half[j], plan, within, corners),
                            _box_box(shape_w[j], shape_w[i], sh_half[j], sh_half[i], plan, within, corners))
            else:
                value = _with_segment(shape_w, i, j, plan, within, ends, a, b)
        best = min(best, value)
    return best


@njit_cached
def _box_box(ws: np.ndarray, wb: np.ndarray, half: np.ndarray, box_half: np.ndarray, plan: KernelPlan,
             within: float, corners: np.ndarray) -> float:
    """Clearance [m] of the twelve edges of a box (frame ``ws``, half extents ``half``) to another (``wb``,
    ``box_half``); ``corners`` (8, 3) is scratch."""
    box_corners, box_edges, grid, rounds = plan.box_corners, plan.box_edges, plan.grid, plan.rounds
    for c in range(8):
        x = box_corners[c, 0] * half[0]
        y = box_corners[c, 1] * half[1]
        z = box_corners[c, 2] * half[2]
        for k in range(3):                                     # R_b^T (o_s + R_s x - o_b)
            corners[c, k] = ((ws[0, 3] + ws[0, 0] * x + ws[0, 1] * y + ws[0, 2] * z - wb[0, 3]) * wb[0, k]
                             + (ws[1, 3] + ws[1, 0] * x + ws[1, 1] * y + ws[1, 2] * z - wb[1, 3]) * wb[1, k]
                             + (ws[2, 3] + ws[2, 0] * x + ws[2, 1] * y + ws[2, 2] * z - wb[2, 3]) * wb[2, k])
    sq = 0.0                                                   # the corners' bounding box against the box: a
    for k in range(3):                                         # lower bound that settles most pairs at once
        lo, hi = corners[0, k], corners[0, k]
        for c in range(1, 8):
            lo, hi = min(lo, corners[c, k]), max(hi, corners[c, k])
        o = max(max(lo - box_half[k], -box_half[k] - hi), 0.0)
        sq += o * o
    if math.sqrt(sq) >= within:
        return math.sqrt(sq)
    value = np.inf
    for e in range(box_edges.shape[0]):
        value = min(value, _segment_box(corners[box_edges[e, 0]], corners[box_edges[e, 1]], box_half, 0.0, within,
                                        grid, rounds))
    return value


@njit_cached
def _with_segment(shape_w: np.ndarray, i: int, j: int, plan: KernelPlan, within: float, ends: np.ndarray,
                  a: np.ndarray, b: np.ndarray) -> float:
    """Clearance [m] of shapes ``i`` and ``j``, at least one a swept segment (``ends``, ``a``, ``b``: scratch)."""
    sh_reach, sh_box, sh_half, sh_radius = plan.sh_reach, plan.sh_box, plan.sh_half, plan.sh_radius
    grid, rounds = plan.grid, plan.rounds
    for n, s in enumerate((i, j)):                             # segment ends in the world: o -+ reach z
        w = shape_w[s]
        for k in range(3):
            ends[2 * n, k] = w[k, 3] - sh_reach[s] * w[k, 2]
            ends[2 * n + 1, k] = w[k, 3] + sh_reach[s] * w[k, 2]
    if sh_box[i] or sh_box[j]:
        seg, box, first = (j, i, 2) if sh_box[i] else (i, j, 0)
        _into(ends[first], shape_w[box], a)
        _into(ends[first + 1], shape_w[box], b)
        return _segment_box(a, b, sh_half[box], sh_radius[seg], within, grid, rounds)
    rims: float = sh_radius[i] + sh_radius[j]
    return _segment_segment(ends[0], ends[1], ends[2], ends[3]) - rims
