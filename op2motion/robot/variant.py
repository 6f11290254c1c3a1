"""A body that differs from the spec's by what we do not know: the torso's centre of mass shifted, its mass scaled.

The OP2's mass distribution is known only within bounds (the spec's figures name their sources and uncertainties);
a check that must hold for the real robot runs on variants of the spec. :func:`spec_variant` returns a new
:class:`~op2motion.robot.spec.Spec` (with its own content hash, so every cache built from a spec keeps them apart)
whose torso (the root link) centre of mass is moved by a vector [m] in the torso frame and whose torso mass and
inertia are scaled.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import replace
from typing import Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.spec import Spec

MAX_SHIFT_M = 0.1           # a torso CoM moved further than this is not the OP2's
MASS_SCALE_RANGE = (0.5, 2.0)


def spec_variant(spec: Spec, torso_com_shift_m: Sequence[float] = (0.0, 0.0, 0.0),
                 torso_mass_scale: float = 1.0) -> Spec:
    """``spec`` with the root link's centre of mass moved by ``torso_com_shift_m`` (3,) [m] (torso frame: x forward,
    y left, z up) and its mass and inertia tensor scaled by ``torso_mass_scale``."""
    shift = np.asarray(torso_com_shift_m, dtype=float)
    if shift.shape != (3,) or not np.all(np.isfinite(shift)) or np.abs(shift).max() > MAX_SHIFT_M:
        raise InputError(f"expected 3 finite numbers within ±{MAX_SHIFT_M} m, got {list(torso_com_shift_m)}",
                         "torso_com_shift_m")
    lo, hi = MASS_SCALE_RANGE
    if not (math.isfinite(torso_mass_scale) and lo <= torso_mass_scale <= hi):
        raise InputError(f"expected a factor from {lo} to {hi}, got {torso_mass_scale!r}", "torso_mass_scale")
    if not shift.any() and torso_mass_scale == 1.0:
        return spec
    inertials = []
    for item in spec.inertials:
        if item.link == spec.root_link:
            com = np.asarray(item.com) + shift
            item = replace(item, mass=item.mass * torso_mass_scale,
                           com=(float(com[0]), float(com[1]), float(com[2])),
                           inertia=tuple(v * torso_mass_scale for v in item.inertia))   # type: ignore[arg-type]
        inertials.append(item)
    tag = f"{spec.sha256}|torso_com+{shift.round(9).tolist()}|torso_mass*{torso_mass_scale:.9g}"
    return replace(spec, inertials=tuple(inertials), sha256=hashlib.sha256(tag.encode()).hexdigest())
