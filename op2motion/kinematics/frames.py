"""Batched rigid transforms for the kinematic chains.

A :class:`Frame` holds N homogeneous transforms as the three columns of the rotation and the origin, each a
(3, N) array, so that one NumPy operation updates the whole batch. Composition with a Denavit-Hartenberg joint
(book eq. 2.40, ``DHMat``: Rz(delta) Tz(d) Tx(a) Rx(alpha)) uses precomputed cos/sin of delta and a constant
alpha, which keeps a step to a handful of array operations.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from op2motion.errors import InputError


def _snap(v: float) -> float:
    """Round cos/sin of multiples of pi/2 to exact 0 or ±1 so that constant steps cost nothing."""
    for exact in (0.0, 1.0, -1.0):
        if abs(v - exact) < 1e-15:
            return exact
    return v


@functools.lru_cache(maxsize=None)
def _twist(alpha: float) -> tuple[float, float]:
    """(cos, sin) of a constant D-H twist, snapped."""
    return _snap(math.cos(alpha)), _snap(math.sin(alpha))


@functools.lru_cache(maxsize=None)
def _sparse_columns(rotation: tuple[tuple[float, ...], ...]) -> tuple[tuple[tuple[int, float], ...], ...]:
    """For each column of a constant rotation: the non-zero (row, weight) pairs."""
    return tuple(tuple((k, _snap(rotation[k][j])) for k in range(3) if _snap(rotation[k][j]) != 0.0)
                 for j in range(3))


@dataclass(frozen=True)
class Frame:
    """N transforms: rotation columns ``x``, ``y``, ``z`` and origin ``p``, each (3, N) [m]."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    p: np.ndarray

    @classmethod
    def constant(cls, rotation: Sequence[Sequence[float]], origin: Sequence[float], n: int) -> "Frame":
        """The same transform N times (rotation given as a 3x3 matrix, origin [m])."""
        r = np.asarray(rotation, dtype=float)

        def rep(v: Sequence[float] | np.ndarray) -> np.ndarray:      # a read-only view, N times
            return np.broadcast_to(np.asarray(v, dtype=float)[:, None], (3, n))

        return cls(rep(r[:, 0]), rep(r[:, 1]), rep(r[:, 2]), rep(origin))

    def dh(self, cos_d: np.ndarray, sin_d: np.ndarray, d: float, a: float, alpha: float) -> "Frame":
        """Compose with the D-H matrix of joint angle delta (given as cos/sin), offset d, length a, twist alpha."""
        x = cos_d * self.x + sin_d * self.y
        y = cos_d * self.y - sin_d * self.x
        ca, sa = _twist(alpha)
        if sa == 0.0:
            y2, z2 = (y, self.z) if ca > 0 else (-y, -self.z)
        elif ca == 0.0:
            y2, z2 = (self.z, -y) if sa > 0 else (-self.z, y)
        else:
            y2, z2 = ca * y + sa * self.z, ca * self.z - sa * y
        p = self.p
        if a != 0.0:
            p = p + a * x
        if d != 0.0:
            p = p + d * self.z
        return Frame(x, y2, z2, p)

    def fixed(self, rotation: Sequence[Sequence[float]] | None = None,
              origin: Sequence[float] = (0.0, 0.0, 0.0)) -> "Frame":
        """Compose with a constant transform (the book's "additional transform" matrices)."""
        cols = (self.x, self.y, self.z)
        p = self.point(origin)
        if rotation is None:
            return Frame(self.x, self.y, self.z, p)
        new: list[np.ndarray] = []
        for column in _sparse_columns(tuple(tuple(float(v) for v in row) for row in rotation)):
            acc: np.ndarray | None = None
            for k, w in column:
                term = cols[k] if w == 1.0 else -cols[k] if w == -1.0 else w * cols[k]
                acc = term if acc is None else acc + term
            if acc is None:
                raise InputError(f"expected a rotation matrix, got a zero column in {rotation!r}", "rotation")
            new.append(acc)
        return Frame(new[0], new[1], new[2], p)

    def point(self, local: Sequence[float]) -> np.ndarray:
        """A point given in this frame [m], as (3, N) in the parent frame."""
        p = self.p
        for col, v in zip((self.x, self.y, self.z), local):
            if v != 0.0:
                p = p + v * col
        return p


#: How far a matrix's rows may be from orthonormal for :func:`quat_xyzw` to convert it directly.
ORTHONORMAL_TOL = 1e-12


def quat_xyzw(rot: np.ndarray) -> tuple[float, float, float, float]:
    """A rotation matrix (3, 3) as a unit quaternion (x, y, z, w): the one SciPy's
    ``Rotation.from_matrix(rot).as_quat()`` gives, bit for bit (the quaternion's largest term chosen from the
    diagonal and the trace, the others from the off-diagonal sums, then divided by its length), without loading
    SciPy's spatial module (0.2 s of ``optimize --validate``). A matrix that is not a rotation to
    :data:`ORTHONORMAL_TOL` goes to SciPy, which orthonormalises it first (or refuses a reflection)."""
    m = np.asarray(rot, dtype=float)
    if m.shape != (3, 3) or not (np.abs(m @ m.T - np.eye(3)).max() <= ORTHONORMAL_TOL and np.linalg.det(m) > 0):
        from scipy.spatial.transform import Rotation

        x, y, z, w = (float(v) for v in Rotation.from_matrix(m).as_quat())
        return x, y, z, w
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    largest = int(np.argmax([m[0, 0], m[1, 1], m[2, 2], trace]))
    if largest == 3:
        q = [m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1], 1.0 + trace]
    else:
        i = largest
        j, k = (i + 1) % 3, (i + 2) % 3
        q = [0.0, 0.0, 0.0, m[k, j] - m[j, k]]
        q[i], q[j], q[k] = 1.0 - trace + 2.0 * m[i, i], m[j, i] + m[i, j], m[k, i] + m[i, k]
    length = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    x, y, z, w = (float(v) / length for v in q)
    return x, y, z, w


def eigen_quaternions(rot: np.ndarray) -> np.ndarray:
    """Rotations (K, 3, 3) as quaternions (K, 4) (x, y, z, w): what pinocchio's ``Quaternion(r).coeffs()`` gives
    for each, bit for bit (Eigen's conversion: from the trace where it is positive, else from the largest diagonal
    term), in a few array operations instead of K calls (a planned walk converts its torso poses a dozen times)."""
    m = np.asarray(rot, dtype=float).reshape(-1, 3, 3)
    out = np.empty((len(m), 4))
    trace = m[:, 0, 0] + (m[:, 1, 1] + m[:, 2, 2])                  # summed in Eigen's order
    up = trace > 0.0
    t = np.sqrt(trace[up] + 1.0)
    out[up, 3] = 0.5 * t
    t = 0.5 / t
    for i, (j, k) in enumerate(((2, 1), (0, 2), (1, 0))):
        out[up, i] = (m[up, j, k] - m[up, k, j]) * t
    for n in np.flatnonzero(~up):                                     # a half turn or more: rare, one at a time
        r = m[n]
        i = 1 if r[1, 1] > r[0, 0] else 0
        i = 2 if r[2, 2] > r[i, i] else i
        j, k = (i + 1) % 3, (i + 2) % 3
        t = math.sqrt(r[i, i] - r[j, j] - r[k, k] + 1.0)
        out[n, i] = 0.5 * t
        t = 0.5 / t
        out[n, 3] = (r[k, j] - r[j, k]) * t
        out[n, j] = (r[j, i] + r[i, j]) * t
        out[n, k] = (r[k, i] + r[i, k]) * t
    return out
