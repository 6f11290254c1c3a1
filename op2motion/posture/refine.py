"""Local refinement after the PSO: land the hand within 1 mm while the balance constraints hold.

First the iterated Taylor arm IK on the D-H model (true geometry) moves the reaching arm's three joints; if that
cannot reach, or the arm's moved mass breaks a constraint, SLSQP adjusts all variables inside the search box,
minimising the squared hand error subject to: stability margin >= 0 (the settled CoM inside the br-shrunk
rectangle), the torso's turn under load within its limit, swing foot not below the floor, and the collision shapes
at least SELF_CLEARANCE_M apart. Gradients are central differences of the batched model (one forward call for all
2 x 20 perturbations).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, replace

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.kinematics import forward
from op2motion.kinematics.arm_ik import solve_arm_ik
from op2motion.posture.cost import SAG_TILT_LIMIT_RAD, SELF_CLEARANCE_M, CostModel, CostTerms, PostureProblem
from op2motion.robot.joints import BookAngles
from op2motion.robot.spec import Spec

REFINE_TOL_M = 1e-3          # hand within 1 mm after refinement
FD_STEP_RAD = 1e-6
SLSQP_MAX_ITER = 60


@dataclass(frozen=True)
class Refinement:
    """Refined variables [rad] (book layout), the method that produced them, and their cost terms (D-H)."""

    x: np.ndarray
    method: str
    terms: CostTerms


def feasible(terms: CostTerms, i: int = 0) -> bool:
    """Balance, floor and self-collision constraints hold for pose ``i``."""
    return bool(terms.margin[i] >= 0.0 and terms.swing_lift[i] >= 0.0 and terms.collision[i] == 0.0
                and terms.sag_tilt[i] <= SAG_TILT_LIMIT_RAD)


def refine(x0: np.ndarray, problem: PostureProblem, spec: Spec, bounds: tuple[np.ndarray, np.ndarray]) -> Refinement:
    """Refine a PSO result on the D-H model (see the module docstring)."""
    model = CostModel(replace(problem, model="dh"), spec)
    lo, hi = bounds
    start = BookAngles.from_vector(np.clip(x0, lo, hi), problem.support)
    best = Refinement(start.vector()[0], "pso", model(start))
    if best.terms.hand_error[0] <= REFINE_TOL_M and feasible(best.terms):
        return best
    with contextlib.suppress(Op2MotionError):  # a singular arm: leave it to SLSQP
        delta = np.asarray(problem.target) - _hand(start, problem, spec)
        ik = solve_arm_ik(start, problem.hand, delta, spec, model="dh", tol=REFINE_TOL_M / 10)
        terms = model(ik.angles)
        candidate = Refinement(ik.angles.vector()[0], "arm-ik", terms)
        if feasible(terms) and terms.hand_error[0] <= REFINE_TOL_M:
            return candidate
        if feasible(terms) and terms.hand_error[0] < best.terms.hand_error[0]:
            best = candidate
    slsqp = _slsqp(best.x, model, problem, (lo, hi))
    if slsqp is not None and feasible(slsqp.terms) and (
            not feasible(best.terms) or slsqp.terms.hand_error[0] < best.terms.hand_error[0]):
        best = slsqp
    return best


def _hand(angles: BookAngles, problem: PostureProblem, spec: Spec) -> np.ndarray:
    hand: np.ndarray = forward(angles, spec, "dh").point(problem.hand_point)[0]
    return hand


def _slsqp(x0: np.ndarray, model: CostModel, problem: PostureProblem,
           bounds: tuple[np.ndarray, np.ndarray]) -> Refinement | None:
    lo, hi = bounds
    support = problem.support
    eye = np.eye(x0.size) * FD_STEP_RAD

    def batch(x: np.ndarray) -> tuple[CostTerms, np.ndarray]:
        probes = np.vstack([x, x + eye, x - eye])
        terms = model(BookAngles.from_vector(probes, support))
        return terms, probes

    cache: dict[bytes, tuple[tuple[float, np.ndarray], ...]] = {}       # (value, gradient) of each function

    def values(x: np.ndarray) -> tuple[tuple[float, np.ndarray], ...]:
        key = x.tobytes()
        if key not in cache:
            terms, _ = batch(x)
            n = x.size

            def split(v: np.ndarray) -> tuple[float, np.ndarray]:
                return float(v[0]), (v[1:n + 1] - v[n + 1:]) / (2 * FD_STEP_RAD)

            err2 = terms.hand_error ** 2
            cache.clear()
            cache[key] = (split(err2), split(terms.margin), split(terms.swing_lift),
                          split(SAG_TILT_LIMIT_RAD - np.minimum(terms.sag_tilt, 1.0)),
                          split(terms.clearance - SELF_CLEARANCE_M))
        return cache[key]

    from scipy.optimize import minimize

    res = minimize(lambda x: values(x)[0][0], x0, jac=lambda x: values(x)[0][1], method="SLSQP",
                   bounds=list(zip(lo, hi)),
                   constraints=[{"type": "ineq", "fun": lambda x, k=k: values(x)[k][0],
                                 "jac": lambda x, k=k: values(x)[k][1]} for k in (1, 2, 3, 4)],
                   options={"maxiter": SLSQP_MAX_ITER, "ftol": 1e-14})
    if not np.all(np.isfinite(res.x)):
        return None
    x = np.clip(res.x, lo, hi)
    return Refinement(x, "slsqp", model(BookAngles.from_vector(x, support)))
