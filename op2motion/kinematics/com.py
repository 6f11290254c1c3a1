"""Lumped-mass centre of mass from body points (book eqs. 2.79/2.88/2.133).

Each lumped mass of the spec (table 2.8) sits at a fixed fraction between two named body points, so the CoM is
one weighted sum over the point rows; both kinematic models use it, inside their chunks while the points are hot.
"""

from __future__ import annotations

import numpy as np

from op2motion.errors import SpecError
from op2motion.kinematics.points import ALL_ROWS, row_of
from op2motion.robot.spec import Spec

_WEIGHTS: dict[str, np.ndarray] = {}


def mass_weights(spec: Spec) -> np.ndarray:
    """Mass [kg] attributed to each body-point row, so that CoM = sum(w * point) / sum(w)."""
    key = spec.sha256
    if key not in _WEIGHTS:
        w = np.zeros(len(ALL_ROWS))
        for m in spec.lumped_masses:
            try:
                a, b = row_of(m.start), row_of(m.end)
            except KeyError as exc:
                raise SpecError(f"{spec.path}: lumped_mass {m.name!r}: unknown body point {exc.args[0]!r}") from None
            w[a] += m.mass * (1.0 - m.fraction)
            w[b] += m.mass * m.fraction
        _WEIGHTS[key] = w
    return _WEIGHTS[key]


def slab_com(slab: np.ndarray, spec: Spec) -> np.ndarray:
    """Lumped CoM (3, N) [m] of a (rows, 3, N) point slab."""
    w = mass_weights(spec)
    com: np.ndarray = np.einsum("k,kij->ij", w / w.sum(), slab)  # no BLAS: its threads would fight the chunk threads
    return com
