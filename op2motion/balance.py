"""Static balance: lumped centre of mass, the support rectangle, the book's penalties and the stability margin.

Centre of mass (book eqs. 2.79/2.88/2.133): the lumped link masses of the spec (table 2.8), each at a fixed
fraction between two named body points, so both kinematic models share one computation. The support polygon is
the support foot's sole rectangle (front, back, inner, outer; inner/outer swap with the foot) shrunk by the
boundary ratio ``br`` (book code 2.9). The stability margin is the signed distance [m] from the CoM's ground
projection to the edge of the shrunk rectangle, positive inside. Everything is vectorised over the batch.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError
from .kinematics.points import BodyPoints
from .spec import Spec

PENALTY = 100.0  # the book's penalty value (code 2.8, 2.9)
FLOOR_TOLERANCE_M = 1e-9  # a swing foot this close to the floor counts as on it (rounding of a flat foot)
COM_MODEL_LUMPED = "lumped (book table 2.8 masses at link midpoints)"


def com_lumped(points: BodyPoints, spec: Spec) -> np.ndarray:
    """Lumped-mass centre of mass of each pose, (N, 3) [m] in the world frame (computed by the models)."""
    return points.com.T


def support_extents(spec: Spec, support: str, br: float = 1.0) -> tuple[float, float, float, float]:
    """(front, back, left, right) half-extents [m] of the br-shrunk support rectangle about the sole centre."""
    if not (np.isfinite(br) and 0.0 < br <= 1.0):
        raise InputError(f"br: expected a boundary ratio in (0, 1], got {br!r}")
    f = spec.foot
    left, right = (f.outer, f.inner) if support == "left" else (f.inner, f.outer)
    return br * f.front, br * f.back, br * left, br * right


def support_polygon(spec: Spec, support: str, br: float = 1.0, sp: tuple[float, float] = (0.0, 0.0),
                    gamma: float = 0.0) -> np.ndarray:
    """Corners (4, 2) [m] of the br-shrunk support rectangle in the world XY plane."""
    front, back, left, right = support_extents(spec, support, br)
    local = np.array([[front, left], [front, -right], [-back, -right], [-back, left]])
    c, s = np.cos(gamma), np.sin(gamma)
    return local @ np.array([[c, s], [-s, c]]) + np.asarray(sp, dtype=float)


def _local(xy: np.ndarray, sp: tuple[float, float], gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """World XY (N, 2) -> support-foot frame coordinates (dx forward, dy left)."""
    d = np.atleast_2d(xy) - np.asarray(sp, dtype=float)
    c, s = np.cos(gamma), np.sin(gamma)
    return c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]


def stability_margin(com_xy: np.ndarray, spec: Spec, support: str, br: float = 1.0,
                     sp: tuple[float, float] = (0.0, 0.0), gamma: float = 0.0) -> np.ndarray:
    """Signed distance (N,) [m] from the CoM ground projection to the shrunk rectangle's edge, positive inside."""
    front, back, left, right = support_extents(spec, support, br)
    dx, dy = _local(com_xy, sp, gamma)
    inside = np.minimum.reduce([front - dx, dx + back, left - dy, dy + right])
    ox = np.maximum(np.maximum(dx - front, -back - dx), 0.0)
    oy = np.maximum(np.maximum(dy - left, -right - dy), 0.0)
    return np.where(inside >= 0.0, inside, -np.hypot(ox, oy))


def penalty_stability(com_xy: np.ndarray, spec: Spec, support: str, br: float = 1.0,
                      sp: tuple[float, float] = (0.0, 0.0), gamma: float = 0.0) -> np.ndarray:
    """Book code 2.9 ``PenaltyStability``: 100 where the CoM leaves the br-shrunk rectangle, else 0; (N,)."""
    front, back, left, right = support_extents(spec, support, br)
    dx, dy = _local(com_xy, sp, gamma)
    outside = (dx > front) | (-dx > back) | (dy > left) | (-dy > right)
    return np.where(outside, PENALTY, 0.0)


def penalty_swing_foot_height(swing_foot_min_z: np.ndarray, des_ht: float = 0.0) -> np.ndarray:
    """Book code 2.8 ``PenaltySwingFootHeight``: 100 where the lowest swing-foot corner is below ``des_ht`` [m]."""
    return np.where(np.asarray(swing_foot_min_z) < des_ht - FLOOR_TOLERANCE_M, PENALTY, 0.0)
