"""Particle swarm optimisation of a posture with pyswarms (book code 2.10 ``pso_posture_opt``).

The book's 20 variables [th(11), phi(6), psi(3)] (17 on the projection model, where psi = 0), searched in the
book's box intersected with the servos' cable-safe limits; GlobalBestPSO with w = 0.8, c1 = c2 = 2, 50 particles,
200 iterations and a velocity clamp of 20 % of each range (all overridable). Positions that leave the box are put
back on its nearest face (``bh_strategy="nearest"``, as the book's min/max), not wrapped around as pyswarms does by
default. ``seed`` makes runs identical.

pyswarms has side effects that must not reach the user: importing it (and creating each optimiser) writes
``report.log`` into the working directory and reconfigures the root logger. :func:`contained_pyswarms` runs those
steps in a private temporary directory and restores the logging configuration afterwards.

Importing ``pyswarms`` loads every optimiser and topology it has (its ring topology loads SciPy's spatial module):
0.4 s of a 1-s ``optimize``. :func:`global_best_pso` loads just ``GlobalBestPSO`` and what it imports (pyswarms' own
modules, unchanged: the star topology, the backend, the base class, the reporter), with
:func:`op2motion.processes.imports.lean_import`.
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

from op2motion import book
from op2motion.errors import InputError
from op2motion.posture.cost import CostModel, PostureProblem
from op2motion.robot.joints import N_PHI, N_TH, BookAngles, book_bounds
from op2motion.robot.spec import BOOK_VARS, Spec
from op2motion.robot.support import Support

MAX_PARTICLES = 10_000
MAX_ITERATIONS = 100_000
MAX_SEED = 2**32 - 1     # NumPy's legacy seeding takes 32-bit seeds


@dataclass(frozen=True)
class PSOSettings:
    """PSO parameters (book code 2.10 defaults)."""

    particles: int = book.PSO_PARTICLES
    iterations: int = book.PSO_ITERATIONS
    w: float = book.PSO_W
    c1: float = book.PSO_C1
    c2: float = book.PSO_C2
    velocity_fraction: float = 0.2
    seed: int = 0

    def validated(self) -> "PSOSettings":
        """Check the values; raise :class:`InputError` naming the parameter on bad ones."""
        for name, value, lo, hi in (("particles", self.particles, 2, MAX_PARTICLES),
                                    ("iterations", self.iterations, 1, MAX_ITERATIONS),
                                    ("seed", self.seed, 0, MAX_SEED)):
            if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
                raise InputError(f"expected a whole number from {lo} to {hi}, got {value!r}", name)
        for name, weight in (("w", self.w), ("c1", self.c1), ("c2", self.c2)):
            if not (math.isfinite(weight) and weight >= 0):
                raise InputError(f"expected a finite non-negative number, got {weight!r}", name)
        if not 0.0 < self.velocity_fraction <= 1.0:
            raise InputError(f"expected (0, 1], got {self.velocity_fraction}", "velocity_fraction")
        return self


@dataclass(frozen=True)
class SearchSpace:
    """Where a swarm searches instead of the default box: ``bounds`` (lo, hi) (20,) each [rad, book variables]
    (a variable pinned by lo == hi) and, optionally, a ``start`` vector (20,) that is one of the first particles."""

    bounds: tuple[np.ndarray, np.ndarray]
    start: np.ndarray | None = None

    def pinned(self, width: float = 1e-7) -> tuple[np.ndarray, np.ndarray]:
        """The bounds with each pinned variable given a width of ``width`` [rad] (a swarm needs lo < hi)."""
        lo, hi = (np.asarray(b, dtype=float).copy() for b in self.bounds)
        tight = hi - lo < width
        lo[tight], hi[tight] = lo[tight] - width / 2, hi[tight] + width / 2
        return lo, hi


@dataclass(frozen=True)
class PSOResult:
    """Best vector [rad] (book layout, 20 values), its cost, the best cost after each iteration and the hand error
    [m] of the best particle so far after each iteration."""

    x: np.ndarray
    cost: float
    history: np.ndarray
    hand_error_history: np.ndarray


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


#: pyswarms' packages whose ``__init__`` loads all of it (every optimiser, every topology), skipped by
#: :func:`global_best_pso`, and what the stand-in of the topology package must hold for GlobalBestPSO's imports.
_PYSWARMS_SKIPPED = ("pyswarms", "pyswarms.single", "pyswarms.backend.topology")
_PYSWARMS_PROVIDES = {"pyswarms.backend.topology": {"Star": "star", "Topology": "base"}}


def global_best_pso() -> Any:
    """pyswarms' ``GlobalBestPSO`` class, loaded without the rest of pyswarms (see the module docstring)."""
    from op2motion.processes.imports import lean_import

    return lean_import("pyswarms.single.global_best", _PYSWARMS_SKIPPED, _PYSWARMS_PROVIDES).GlobalBestPSO


def variable_bounds(problem: PostureProblem, spec: Spec) -> tuple[np.ndarray, np.ndarray]:
    """Search box [rad] for the 20 book variables: the book's box (code 2.10) within the servo limits."""
    servo_lo, servo_hi = book_bounds(spec, problem.support)
    lo = np.maximum(np.radians(book.PSO_LOWER_DEG), servo_lo)
    hi = np.minimum(np.radians(book.PSO_UPPER_DEG), servo_hi)
    if np.any(lo >= hi):
        k = int(np.argmax(lo >= hi))
        raise InputError("the book's range and the servo limits do not overlap", BOOK_VARS[k])
    return lo, hi


def run_pso(problem: PostureProblem, spec: Spec, settings: PSOSettings = PSOSettings(),
            on_iteration: Callable[[float], Any] | None = None, space: SearchSpace | None = None) -> PSOResult:
    """Minimise the posture cost with pyswarms' GlobalBestPSO; ``on_iteration(best_cost)`` is called each step;
    ``space`` narrows the box (pinned variables) and seeds a particle at its start."""
    problem, settings = problem.validated(), settings.validated()
    lo, hi = variable_bounds(problem, spec) if space is None else space.pinned()
    full = lo.size
    dims = N_TH + N_PHI if problem.model == "pb" else full  # the projection model has psi = 0
    lo, hi = lo[:dims], hi[:dims]
    v_max = settings.velocity_fraction * (hi - lo)
    best, best_hand, hand_history = [math.inf], [math.inf], []
    cost_model = CostModel(problem, spec)
    plan = cost_model.kernel_plan()
    personal = np.full(settings.particles, np.inf)   # each particle's best cost, as pyswarms keeps it
    support = Support.single(problem.support)
    if plan is not None:
        from op2motion.posture.kernel import HAND_ERROR, TOTAL, swarm_terms

    def objective(swarm: np.ndarray) -> np.ndarray:
        x = swarm if dims == full else np.hstack([swarm, np.zeros((swarm.shape[0], full - dims))])
        # a particle that cannot beat its personal best skips the self-collision check (the search is unchanged)
        if plan is not None:                          # the compiled loop (same terms as the NumPy model)
            terms = swarm_terms(plan, x, personal)
            total, hand = terms[:, TOTAL], terms[:, HAND_ERROR]
        else:
            numpy_terms = cost_model(BookAngles(x[:, :N_TH], x[:, N_TH:N_TH + N_PHI], x[:, N_TH + N_PHI:], support),
                                     only_below=personal)
            total, hand = numpy_terms.total, numpy_terms.hand_error
        np.minimum(personal, total, out=personal)
        i = int(np.argmin(total))
        if total[i] < best[0]:
            best[0], best_hand[0] = float(total[i]), float(hand[i])
        hand_history.append(best_hand[0])
        if on_iteration is not None:
            on_iteration(best[0])
        return total

    state = np.random.get_state()
    np.random.seed(settings.seed)  # pyswarms draws from NumPy's global generator
    try:
        with contained_pyswarms():
            GlobalBestPSO = global_best_pso()
            init = None
            if space is not None and space.start is not None:     # the start among uniform draws in the box
                init = lo + (hi - lo) * np.random.uniform(size=(settings.particles, dims))
                init[0] = np.clip(np.asarray(space.start, dtype=float)[:dims], lo, hi)
            optimizer = GlobalBestPSO(n_particles=settings.particles, dimensions=dims,
                                      options={"w": settings.w, "c1": settings.c1, "c2": settings.c2},
                                      bounds=(lo, hi), velocity_clamp=(-v_max, v_max), bh_strategy="nearest",
                                      init_pos=init)
        with contained_pyswarms():
            cost, pos = optimizer.optimize(objective, iters=settings.iterations, verbose=False)
    finally:
        np.random.set_state(state)
    x = np.zeros(full)
    x[:dims] = pos
    return PSOResult(x, float(cost), np.asarray(optimizer.cost_history, dtype=float), np.asarray(hand_history))
