"""Particle swarm optimisation of a posture with pyswarms (book code 2.10 ``pso_posture_opt``).

The book's 20 variables [th(11), phi(6), psi(3)] (17 on the projection model, where psi = 0), searched in the
book's box intersected with the servos' cable-safe limits; GlobalBestPSO with w = 0.8, c1 = c2 = 2, 50 particles,
200 iterations and a velocity clamp of 20 % of each range (all overridable). Positions that leave the box are put
back on its nearest face (``bh_strategy="nearest"``, as the book's min/max), not wrapped around as pyswarms does by
default. ``seed`` makes runs identical.

pyswarms has side effects that must not reach the user: importing it (and creating each optimiser) writes
``report.log`` into the working directory and reconfigures the root logger. :func:`contained_pyswarms` runs those
steps in a private temporary directory and restores the logging configuration afterwards.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import shutil
import tempfile
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from ..errors import InputError
from ..joints import BOOK_PSO_LOWER_DEG, BOOK_PSO_UPPER_DEG, N_PHI, N_TH, BookAngles
from ..spec import BOOK_VARS, Spec
from .cost import CostModel, PostureProblem


@dataclass(frozen=True)
class PSOSettings:
    """PSO parameters (book code 2.10 defaults)."""

    particles: int = 50
    iterations: int = 200
    w: float = 0.8
    c1: float = 2.0
    c2: float = 2.0
    velocity_fraction: float = 0.2
    seed: int = 0

    def validated(self) -> "PSOSettings":
        """Check the values; raise :class:`InputError` on bad ones."""
        if not (2 <= self.particles <= 10_000 and 1 <= self.iterations <= 100_000):
            raise InputError(f"particles/iterations: expected 2..10000 and 1..100000, got {self.particles}, "
                             f"{self.iterations}")
        if not all(math.isfinite(v) and v >= 0 for v in (self.w, self.c1, self.c2)):
            raise InputError("w, c1, c2: expected finite non-negative numbers")
        if not 0.0 < self.velocity_fraction <= 1.0:
            raise InputError(f"velocity_fraction: expected (0, 1], got {self.velocity_fraction}")
        return self


@dataclass(frozen=True)
class PSOResult:
    """Best vector [rad] (book layout, 20 values), its cost, and the best cost after each iteration."""

    x: np.ndarray
    cost: float
    history: np.ndarray


@contextlib.contextmanager
def contained_pyswarms() -> Iterator[None]:
    """Run pyswarms' import or construction with its report.log and logging changes kept out of the user's way."""
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    manager = logging.Logger.manager
    disabled = {name: lg.disabled for name, lg in manager.loggerDict.items() if isinstance(lg, logging.Logger)}
    cwd = os.getcwd()
    scratch = tempfile.mkdtemp(prefix="op2motion-pyswarms-")
    os.chdir(scratch)
    try:
        yield
    finally:
        os.chdir(cwd)
        for handler in root.handlers[:]:
            if handler not in handlers:
                root.removeHandler(handler)
                handler.close()
        for handler in handlers:  # dictConfig removed the user's own handlers: put them back
            if handler not in root.handlers:
                root.addHandler(handler)
        root.setLevel(level)
        for name, lg in manager.loggerDict.items():
            if isinstance(lg, logging.Logger):
                if name.startswith("pyswarms"):
                    for handler in lg.handlers[:]:
                        lg.removeHandler(handler)
                        handler.close()
                elif name in disabled:
                    lg.disabled = disabled[name]
        logging.getLogger("pyswarms").setLevel(logging.WARNING)  # its per-iteration INFO records go nowhere
        shutil.rmtree(scratch, ignore_errors=True)


def variable_bounds(problem: PostureProblem, spec: Spec) -> tuple[np.ndarray, np.ndarray]:
    """Search box [rad] for the 20 book variables: the book's box (code 2.10) within the servo limits."""
    lo, hi = np.radians(BOOK_PSO_LOWER_DEG).astype(float), np.radians(BOOK_PSO_UPPER_DEG).astype(float)
    for joint in spec.joints:
        m = joint.book[problem.support]
        k = BOOK_VARS.index(m.var)
        a, b = sorted(((joint.lower - m.offset) * m.sign, (joint.upper - m.offset) * m.sign))
        lo[k], hi[k] = max(lo[k], a), min(hi[k], b)
    if np.any(lo >= hi):
        k = int(np.argmax(lo >= hi))
        raise InputError(f"{BOOK_VARS[k]}: the book's range and the servo limits do not overlap")
    return lo, hi


def run_pso(problem: PostureProblem, spec: Spec, settings: PSOSettings = PSOSettings(),
            on_iteration: Callable[[float], Any] | None = None) -> PSOResult:
    """Minimise the posture cost with pyswarms' GlobalBestPSO; ``on_iteration(best_cost)`` is called each step."""
    problem, settings = problem.validated(), settings.validated()
    lo, hi = variable_bounds(problem, spec)
    full = lo.size
    dims = N_TH + N_PHI if problem.model == "pb" else full  # the projection model has psi = 0
    lo, hi = lo[:dims], hi[:dims]
    v_max = settings.velocity_fraction * (hi - lo)
    best = [math.inf]
    cost_model = CostModel(problem, spec)

    def objective(swarm: np.ndarray) -> np.ndarray:
        x = swarm if dims == full else np.hstack([swarm, np.zeros((swarm.shape[0], full - dims))])
        cost = cost_model(BookAngles(x[:, :N_TH], x[:, N_TH:N_TH + N_PHI], x[:, N_TH + N_PHI:], problem.support)).total
        best[0] = min(best[0], float(cost.min()))
        if on_iteration is not None:
            on_iteration(best[0])
        return cost

    state = np.random.get_state()
    np.random.seed(settings.seed)  # pyswarms draws from NumPy's global generator
    try:
        with contained_pyswarms():
            from pyswarms.single import GlobalBestPSO

            optimizer = GlobalBestPSO(n_particles=settings.particles, dimensions=dims,
                                      options={"w": settings.w, "c1": settings.c1, "c2": settings.c2},
                                      bounds=(lo, hi), velocity_clamp=(-v_max, v_max), bh_strategy="nearest")
        with contained_pyswarms():
            cost, pos = optimizer.optimize(objective, iters=settings.iterations, verbose=False)
    finally:
        np.random.set_state(state)
    x = np.zeros(full)
    x[:dims] = pos
    return PSOResult(x, float(cost), np.asarray(optimizer.cost_history, dtype=float))
