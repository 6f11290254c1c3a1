"""Static balance: the support rectangle, the book's penalties and the stability margin.

The support polygon of a single-support pose is the support foot's sole rectangle (:meth:`Foot.extents`: front,
back, inner, outer; inner/outer swap with the foot) shrunk by the boundary ratio ``br`` (book code 2.9). The
stability margin is the signed distance [m] from the CoM's ground projection to the edge of the shrunk rectangle,
positive inside: :func:`rectangle_margin` computes it for a whole batch and is the one implementation that the
posture cost, the reports and the physics verdict share. Which centre of mass a margin was measured from is the
caller's to state (:data:`COM_MODEL_LUMPED`, :data:`COM_MODEL_FULL`).
"""

from __future__ import annotations

import math
from typing import Final, Literal, get_args

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.sides import Side
from op2motion.robot.spec import Spec

PENALTY = 100.0  # the book's penalty value (code 2.8, 2.9)
FLOOR_TOLERANCE_M = 1e-9  # a swing foot this close to the floor counts as on it (rounding of a flat foot)
#: Which centre of mass: the spec's per-link inertials (``full``) or the book's lumped masses (``book``).
ComModel = Literal["full", "book"]
COM_MODEL_LUMPED: Final = "book"   # the book's lumped link masses (table 2.8) at link midpoints
COM_MODEL_FULL: Final = "full"     # the spec's per-link inertials (Webots masses, CoMs and tensors)
COM_MODELS: tuple[ComModel, ...] = get_args(ComModel)
COM_MODEL_TEXT = {COM_MODEL_LUMPED: "lumped: the book's table 2.8 masses at link midpoints",
                  COM_MODEL_FULL: "full inertia: the spec's per-link masses and centres of mass"}


def check_br(br: float) -> float:
    """Return ``br`` if it is a boundary ratio in (0, 1], else raise :class:`InputError`."""
    if not (isinstance(br, (int, float)) and np.isfinite(br) and 0.0 < br <= 1.0):
        raise InputError(f"expected a boundary ratio in (0, 1], got {br!r}", "br")
    return float(br)


def support_extents(spec: Spec, support: Side, br: float = 1.0,
                    com_model: ComModel = COM_MODEL_LUMPED) -> tuple[float, float, float, float]:
    """The support rectangle (front, back, left, right) [m] about the sole centre, shrunk by ``br``, that goes with
    a CoM model: the book's foot (table 2.7) for the book's lumped CoM, the real sole (the foot box) for the
    full-inertia CoM."""
    check_br(br)
    if com_model == COM_MODEL_FULL:
        return spec.sole_extents(support, br)
    return spec.foot.extents(support, br)


def rectangle_margin(dx: np.ndarray, dy: np.ndarray, extents: tuple[float, float, float, float]) -> np.ndarray:
    """Signed distance [m] from points (dx forward, dy left) [m] to the edge of the rectangle
    (front, back, left, right) about the origin: positive inside, the Euclidean distance outside; (N,)."""
    front, back, left, right = extents
    inside = np.minimum(np.minimum(front - dx, dx + back), np.minimum(left - dy, dy + right))
    outside = np.hypot(np.maximum(np.maximum(dx - front, -back - dx), 0.0),
                       np.maximum(np.maximum(dy - left, -right - dy), 0.0))
    return np.where(inside >= 0.0, inside, -outside)


def support_polygon(spec: Spec, support: Side, br: float = 1.0, sp: tuple[float, float] = (0.0, 0.0),
                    gamma: float = 0.0, com_model: ComModel = COM_MODEL_LUMPED) -> np.ndarray:
    """Corners (4, 2) [m] of the br-shrunk support rectangle of ``com_model`` in the world XY plane."""
    front, back, left, right = support_extents(spec, support, br, com_model)
    local = np.array([[front, left], [front, -right], [-back, -right], [-back, left]])
    c, s = np.cos(gamma), np.sin(gamma)
    corners: np.ndarray = local @ np.array([[c, s], [-s, c]]) + np.asarray(sp, dtype=float)
    return corners


def _local(xy: np.ndarray, sp: tuple[float, float], gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """World XY (N, 2) -> support-foot frame coordinates (dx forward, dy left)."""
    d = np.atleast_2d(xy) - np.asarray(sp, dtype=float)
    c, s = np.cos(gamma), np.sin(gamma)
    return c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]


def stability_margin(com_xy: np.ndarray, spec: Spec, support: Side, br: float = 1.0,
                     sp: tuple[float, float] = (0.0, 0.0), gamma: float = 0.0,
                     com_model: ComModel = COM_MODEL_LUMPED) -> np.ndarray:
    """Signed distance (N,) [m] from the CoM ground projection to the edge of the rectangle that goes with
    ``com_model`` (:func:`support_extents`), shrunk by ``br``; positive inside."""
    dx, dy = _local(com_xy, sp, gamma)
    return rectangle_margin(dx, dy, support_extents(spec, support, br, com_model))


def penalty_stability(com_xy: np.ndarray, spec: Spec, support: Side, br: float = 1.0,
                      sp: tuple[float, float] = (0.0, 0.0), gamma: float = 0.0) -> np.ndarray:
    """Book code 2.9 ``PenaltyStability``: 100 where the CoM leaves the br-shrunk rectangle, else 0; (N,)."""
    front, back, left, right = spec.foot.extents(support, check_br(br))
    dx, dy = _local(com_xy, sp, gamma)
    outside = (dx > front) | (-dx > back) | (dy > left) | (-dy > right)
    return np.where(outside, PENALTY, 0.0)


def penalty_swing_foot_height(swing_foot_min_z: np.ndarray, des_ht: float = 0.0) -> np.ndarray:
    """Book code 2.8 ``PenaltySwingFootHeight``: 100 where the lowest swing-foot corner is below ``des_ht`` [m]."""
    return np.where(np.asarray(swing_foot_min_z) < des_ht - FLOOR_TOLERANCE_M, PENALTY, 0.0)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Convex hull (m, 2) of points (n, 2) [m], counter-clockwise, without repeated or collinear points."""
    pts = sorted(set(map(tuple, np.asarray(points, dtype=float).reshape(-1, 2).tolist())))
    if len(pts) < 3:
        return np.asarray(pts, dtype=float).reshape(-1, 2)

    def half(seq: list[tuple[float, ...]]) -> list[tuple[float, ...]]:
        out: list[tuple[float, ...]] = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 1e-15:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.asarray(lower[:-1] + upper[:-1], dtype=float)


def polygon_margin(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Signed distance (N,) [m] from points (N, 2) to the edge of a convex counter-clockwise polygon (m, 2):
    positive inside, the Euclidean distance to the polygon outside."""
    p = np.atleast_2d(np.asarray(xy, dtype=float))
    a, b = polygon, np.roll(polygon, -1, axis=0)
    edge = b - a                                                     # (m, 2)
    length = np.hypot(edge[:, 0], edge[:, 1])
    rel = p[:, None, :] - a[None, :, :]                              # (N, m, 2)
    # distance to each edge's line, positive on the inner (left) side of a counter-clockwise polygon
    signed = (edge[None, :, 0] * rel[:, :, 1] - edge[None, :, 1] * rel[:, :, 0]) / length[None, :]
    inside = signed.min(axis=1)
    t = np.clip(np.einsum("nmk,mk->nm", rel, edge) / (length ** 2)[None, :], 0.0, 1.0)
    nearest = a[None, :, :] + t[:, :, None] * edge[None, :, :]
    outside = np.hypot(*(p[:, None, :] - nearest).transpose(2, 0, 1)).min(axis=1)
    margin: np.ndarray = np.where(inside >= 0.0, inside, -outside)
    return margin


def point_margin(x: float, y: float, polygon: np.ndarray) -> float:
    """:func:`polygon_margin` of one point (``x``, ``y``) [m], on floats: the per-sample callers (a run's support
    margins, a plan's ZMP margins) ask for one point at a time, where NumPy's call overhead was most of the cost."""
    corners = polygon.tolist()
    if len(corners) < 3:                      # a degenerate polygon: the array version's answer, whatever it is
        return float(polygon_margin(np.array([x, y]), polygon)[0])
    inside = outside = math.inf
    for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1]):
        ex, ey = bx - ax, by - ay
        length = math.hypot(ex, ey)
        rx, ry = x - ax, y - ay
        inside = min(inside, (ex * ry - ey * rx) / length)         # positive on the inner (left) side
        t = min(max((rx * ex + ry * ey) / length ** 2, 0.0), 1.0)  # the nearest point of the edge
        outside = min(outside, math.hypot(x - (ax + t * ex), y - (ay + t * ey)))
    return inside if inside >= 0.0 else -outside
