"""One 3-vector or one 3 x 3 matrix at a time, as plain tuples: the arithmetic of per-tick code.

A walk controller turns a handful of single vectors and rotations every 8 ms. On arrays this small NumPy's cost is
its call overhead (about a microsecond per operation, tens of them per tick, plus building each rotation), not the
arithmetic: the same products written out on floats cost a fraction of that. Batched work (rows of a plan, IK over
a walk) stays on NumPy (:mod:`.leg_ik`). A vector is ``(x, y, z)``, a matrix a tuple of its three rows; both accept
any sequence (a list from ``ndarray.tolist()`` too). The results equal NumPy's to rounding (a few 1e-16).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]
IDENTITY: Mat3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def vec(v: np.ndarray | Sequence[float]) -> Vec3:
    """A vector (3,) as a tuple of floats."""
    x, y, z = v.tolist() if isinstance(v, np.ndarray) else v
    return (float(x), float(y), float(z))


def mat(m: np.ndarray | Sequence[Sequence[float]]) -> Mat3:
    """A matrix (3, 3) as a tuple of its rows."""
    a, b, c = m.tolist() if isinstance(m, np.ndarray) else m
    return (vec(a), vec(b), vec(c))


def rot_x(a: float) -> Mat3:
    """The rotation about X by ``a`` [rad] (:func:`.leg_ik.rot_x` for one angle)."""
    c, s = math.cos(a), math.sin(a)
    return ((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c))


def rot_y(a: float) -> Mat3:
    """The rotation about Y by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return ((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c))


def rot_z(a: float) -> Mat3:
    """The rotation about Z by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))


def add(u: Sequence[float], v: Sequence[float]) -> Vec3:
    """u + v."""
    return (u[0] + v[0], u[1] + v[1], u[2] + v[2])


def sub(u: Sequence[float], v: Sequence[float]) -> Vec3:
    """u - v."""
    return (u[0] - v[0], u[1] - v[1], u[2] - v[2])


def scaled(v: Sequence[float], s: float) -> Vec3:
    """v * s."""
    return (v[0] * s, v[1] * s, v[2] * s)


def apply(m: Sequence[Sequence[float]], v: Sequence[float]) -> Vec3:
    """m @ v."""
    (a, b, c), (d, e, f), (g, h, i) = m
    x, y, z = v
    return (a * x + b * y + c * z, d * x + e * y + f * z, g * x + h * y + i * z)


def apply_t(m: Sequence[Sequence[float]], v: Sequence[float]) -> Vec3:
    """m.T @ v (a rotation's inverse applied)."""
    (a, b, c), (d, e, f), (g, h, i) = m
    x, y, z = v
    return (a * x + d * y + g * z, b * x + e * y + h * z, c * x + f * y + i * z)


def mul(m: Sequence[Sequence[float]], n: Sequence[Sequence[float]]) -> Mat3:
    """m @ n."""
    (a, b, c), (d, e, f), (g, h, i) = n
    (p, q, r), (s, t, u), (v, w, x) = m
    return ((p * a + q * d + r * g, p * b + q * e + r * h, p * c + q * f + r * i),
            (s * a + t * d + u * g, s * b + t * e + u * h, s * c + t * f + u * i),
            (v * a + w * d + x * g, v * b + w * e + x * h, v * c + w * f + x * i))


def mul_t(m: Sequence[Sequence[float]], n: Sequence[Sequence[float]]) -> Mat3:
    """m.T @ n."""
    (p, s, v), (q, t, w), (r, u, x) = m
    return mul(((p, q, r), (s, t, u), (v, w, x)), n)


def norm(v: Sequence[float]) -> float:
    """The Euclidean length of v."""
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
