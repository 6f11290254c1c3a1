"""``op2motion bench``: speed figures measured in one run (design.md section 6).

40 000 full-body evaluations (every body point plus the lumped CoM) per kinematic model, poses drawn from the
book's PSO box; the best of ``repeat`` runs is reported, so that one run gives comparable ratios.
"""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from .balance import com_lumped
from .joints import BookAngles, book_to_servo
from .kinematics import forward
from .model.dynamics import dynamics_for
from .physics import validate_servo
from .posture.cost import PostureProblem
from .posture.pso import PSOSettings, run_pso
from .spec import Spec

BENCH_POSES = 40_000



def _best_ms(fn: Callable[[], Any], repeat: int) -> float:
    fn()  # warm caches and tables
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best * 1000.0


def run_bench(spec: Spec, n: int = BENCH_POSES, repeat: int = 9, seed: int = 0) -> dict[str, Any]:
    """Time batched forward kinematics + CoM for ``n`` poses with each model; figures in milliseconds."""
    rng = np.random.default_rng(seed)
    poses_dh = BookAngles.random(n, rng, "left", psi=True)
    poses_pb = BookAngles(poses_dh.th, poses_dh.phi, np.zeros_like(poses_dh.psi), "left")
    full = lambda poses, model: com_lumped(forward(poses, spec, model), spec)  # noqa: E731
    scale = BENCH_POSES / n
    pb_ms = _best_ms(lambda: full(poses_pb, "pb"), repeat) * scale
    dh_ms = _best_ms(lambda: full(poses_dh, "dh"), repeat) * scale
    dyn = dynamics_for(spec)
    servo = book_to_servo(poses_dh, spec)
    pin_ms = _best_ms(lambda: dyn.com_loop(servo), 1) * scale
    stand = book_to_servo(BookAngles.standing("left"), spec)[0]
    validate_ms = _best_ms(lambda: validate_servo(stand, "double", spec, 3.0), 1)
    problem = PostureProblem("left", "left", (0.10, 0.05, 0.07), 0.7)  # optimize's default problem
    pso_ms = _best_ms(lambda: run_pso(problem, spec, PSOSettings()), 3)
    return {
        "poses": n,
        "repeat": repeat,
        "fk_pb_40k_ms": round(pb_ms, 2),
        "fk_dh_40k_ms": round(dh_ms, 2),
        "pinocchio_com_40k_ms": round(pin_ms, 1),
        "validate_ms": round(validate_ms, 1),
        "pso_solve_ms": round(pso_ms, 1),
        "book_matlab_pb_40k_ms": 780.0,
        "book_matlab_dh_40k_ms": 3350.0,
    }
