"""The grid of a library build: hands x supports x boundary ratios x target points, checked before any work.

Sizes are capped before anything is allocated (:data:`MAX_AXIS`, :data:`MAX_TARGETS`), and two targets that
would get the same pose name (closer than 1 mm, or boundary ratios within 1 %) make the grid bad input rather than
overwrite each other.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from op2motion.errors import InputError, ref
from op2motion.posture.cost import PostureProblem
from op2motion.robot.balance import COM_MODEL_FULL, ComModel
from op2motion.robot.support import Side

MAX_AXIS = 1000          # values per grid axis
MAX_TARGETS = 10_000     # targets per build (about 1 s each on one core)


@dataclass(frozen=True)
class Job:
    """One grid point."""

    hand: Side
    support: Side
    br: float
    target: tuple[float, float, float]
    com_model: ComModel = COM_MODEL_FULL

    @property
    def problem(self) -> PostureProblem:
        """The posture problem of this grid point."""
        return PostureProblem(self.support, self.hand, self.target, self.br, com_model=self.com_model)

    @property
    def name(self) -> str:
        """Pose name of this grid point, e.g. ``reach-ll-100-50-70-br70``."""
        return self.problem.name


def axis(start: float, stop: float, count: float, name: str) -> list[float]:
    """``count`` evenly spaced values from ``start`` to ``stop`` [m] (1 <= count <= :data:`MAX_AXIS`)."""
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise InputError(f"expected finite START and STOP, got {start} {stop}", name)
    if not (math.isfinite(count) and float(count).is_integer() and 1 <= count <= MAX_AXIS):
        raise InputError(f"expected a whole COUNT from 1 to {MAX_AXIS}, got {count}", name)
    return [float(v) for v in np.linspace(start, stop, int(count))]


def _axes() -> str:
    return ", ".join(ref(p) for p in ("hands", "supports", "br", "x", "y", "z"))


def grid_jobs(hands: Sequence[Side], supports: Sequence[Side], brs: Sequence[float], xs: Sequence[float],
              ys: Sequence[float], zs: Sequence[float], com_model: ComModel = COM_MODEL_FULL) -> list[Job]:
    """All combinations, each checked; raises :class:`InputError` for too many targets or colliding names."""
    total = len(hands) * len(supports) * len(brs) * len(xs) * len(ys) * len(zs)
    if total > MAX_TARGETS:
        raise InputError(f"expected at most {MAX_TARGETS} targets, got a grid of {total} ({_axes()})")
    if total == 0:
        raise InputError(f"expected at least one target, got an empty grid ({_axes()})")
    jobs = [Job(h, s, float(b), (float(x), float(y), float(z)), com_model)
            for h, s, b, x, y, z in itertools.product(dict.fromkeys(hands), dict.fromkeys(supports), brs, xs, ys, zs)]
    names: dict[str, Job] = {}
    for job in jobs:
        job.problem.validated()
        other = names.setdefault(job.name, job)
        if other is not job:
            raise InputError(f"targets {list(other.target)} (br {other.br}) and {list(job.target)} (br {job.br}) "
                             f"get the same pose name {job.name!r}: space targets at least 1 mm and boundary "
                             f"ratios at least 0.01 apart ({_axes()})")
    return jobs
