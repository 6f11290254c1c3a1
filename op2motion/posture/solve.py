"""One posture solve: PSO, refinement, verdict, with restarts on the next seeds (library function behind
``op2motion optimize`` and ``library build``, through :mod:`op2motion.workflow`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from op2motion.jsonout import JsonObject
from op2motion.kinematics import forward
from op2motion.posture.cost import SAG_TILT_LIMIT_RAD, CostModel, CostTerms, PostureProblem
from op2motion.posture.pso import PSOResult, PSOSettings, SearchSpace, run_pso, variable_bounds
from op2motion.posture.refine import REFINE_TOL_M, feasible, refine
from op2motion.robot.balance import COM_MODEL_FULL, COM_MODEL_LUMPED, rectangle_margin
from op2motion.robot.joints import BookAngles
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec

PSO_TOL_M = 5e-3   # without refinement a hand within 5 mm counts as reaching


def _vec(v: np.ndarray) -> list[float]:
    return [float(x) for x in v]


@dataclass(frozen=True)
class PostureResult:
    """Outcome of :func:`optimize_posture`; every length [m] in the support-foot frame, on the D-H model.

    ``com_lumped``/``margin_lumped_m``: the book's lumped masses, margin to the book's foot rectangle (table 2.7);
    ``com_full``/``margin_full_m``: the spec's per-link inertials, margin to the real sole (the foot box); both
    rectangles shrunk by br. ``problem.com_model`` says which of the two the optimiser balanced.
    """

    problem: PostureProblem
    settings: PSOSettings
    angles: BookAngles
    terms: CostTerms
    pso: PSOResult
    method: str
    seconds: float
    reached: bool
    message: str
    tolerance_m: float
    com_lumped: np.ndarray
    margin_lumped_m: float
    com_full: np.ndarray
    margin_full_m: float
    left_hand: np.ndarray
    right_hand: np.ndarray
    attempts: int = 1
    attempt_pso: tuple[PSOResult, ...] = ()

    @property
    def chosen_attempt(self) -> int:
        """Index (from 0) of the kept attempt among :attr:`attempt_pso`."""
        return next((k for k, p in enumerate(self.attempt_pso) if p is self.pso), len(self.attempt_pso) - 1)

    @property
    def hand_error_m(self) -> float:
        """Distance of the reaching hand from the target [m]."""
        return float(self.terms.hand_error[0])

    @property
    def swing_foot_min_z(self) -> float:
        """Height of the swing foot's lowest corner above the floor [m]."""
        return float(self.terms.swing_min_z[0])

    @property
    def cost(self) -> float:
        """Final cost (book eq. 2.87 and the tie-breakers)."""
        return float(self.terms.total[0])

    def as_dict(self) -> JsonObject:
        """The metrics, JSON-ready (also the ``metrics`` of the pose file)."""
        return {
            "target": list(self.problem.target), "hand_error_m": self.hand_error_m, "br": self.problem.br,
            "balanced_com_model": self.problem.com_model,
            "com": _vec(self.com_lumped), "com_model": COM_MODEL_LUMPED, "stability_margin_m": self.margin_lumped_m,
            "com_full": _vec(self.com_full), "com_full_model": COM_MODEL_FULL,
            "stability_margin_full_m": self.margin_full_m,
            "left_hand": _vec(self.left_hand), "right_hand": _vec(self.right_hand),
            "swing_foot_min_z": self.swing_foot_min_z, "torso_tilt_deg": float(np.degrees(self.terms.tilt[0])),
            "self_clearance_m": float(self.terms.clearance[0]),
            "cost": self.cost, "pso_cost": self.pso.cost, "attempts": self.attempts,
        }

    def pose(self, name: str, spec: Spec, provenance: dict[str, Any] | None = None) -> Pose:
        """The solution as a pose (support = the problem's support foot), metrics and provenance filled in."""
        p = self.problem
        prov = {"target_m": list(p.target), "hand": p.hand, "support": p.support, "br": p.br, "model": p.model,
                "com_model": p.com_model,
                "seed": self.settings.seed, "particles": self.settings.particles,
                "iterations": self.settings.iterations, "refinement": self.method, **(provenance or {})}
        return Pose.from_book(name, self.angles, spec, metrics=self.as_dict(), provenance=prov)


Check = Callable[[PostureResult], tuple[bool, str]]


def optimize_posture(problem: PostureProblem, spec: Spec, settings: PSOSettings = PSOSettings(),
                     refine_result: bool = True, on_iteration: Callable[[float], Any] | None = None,
                     restarts: int = 0, check: Check | None = None, space: SearchSpace | None = None
                     ) -> PostureResult:
    """Find a balanced whole-body pose that puts ``problem.hand`` on ``problem.target``.

    A swarm can settle on the edge of the stability region where refinement stalls, or on a pose the model calls
    balanced but ``check`` (e.g. the physics validation) rejects; ``restarts`` further solves with the next seeds
    are tried until one passes. The best attempt is returned (passing first, then reached, then residual).
    ``space`` narrows the search (pinned variables, a start pose; :class:`.pso.SearchSpace`).
    """
    t0 = time.perf_counter()

    def attempt(seed: int) -> PostureResult:
        res = _solve_once(problem, spec, replace(settings, seed=seed), refine_result, on_iteration, space)
        if res.reached and check is not None:
            ok, why = check(res)
            if not ok:
                res = replace(res, reached=False, message=f"reached, but {why}")
        return res

    best = attempt(settings.seed)
    tried = [best.pso]
    k = 0
    while not best.reached and k < restarts:
        k += 1
        candidate = attempt(settings.seed + k)
        tried.append(candidate.pso)
        if _rank(candidate) > _rank(best):
            best = candidate
    return replace(best, seconds=time.perf_counter() - t0, attempts=k + 1, attempt_pso=tuple(tried))


def _rank(result: PostureResult) -> tuple[bool, bool, float]:
    """Order of preference among attempts: reached, then feasible, then the smaller hand residual."""
    return result.reached, feasible(result.terms), -result.hand_error_m


def _verdict(terms: CostTerms, tol: float) -> tuple[bool, str]:
    error_mm = terms.hand_error[0] * 1000
    if terms.hand_error[0] <= tol and feasible(terms):
        return True, f"reached: hand {error_mm:.2f} mm from the target"
    if not feasible(terms):
        why = ("the CoM leaves the support rectangle" if terms.margin[0] < 0 else
               "the torso turns too far as the servos take the load" if terms.sag_tilt[0] > SAG_TILT_LIMIT_RAD else
               "the swing foot comes too close to the floor" if terms.swing_lift[0] < 0 else
               f"the pose collides with itself (clearance {terms.clearance[0] * 1000:.1f} mm)")
        return False, f"infeasible: {why} (best hand residual {error_mm:.1f} mm)"
    return False, f"unreachable: best hand residual {error_mm:.1f} mm (tolerance {tol * 1000:.0f} mm)"


def _solve_once(problem: PostureProblem, spec: Spec, settings: PSOSettings, refine_result: bool,
                on_iteration: Callable[[float], Any] | None, space: SearchSpace | None = None) -> PostureResult:
    t0 = time.perf_counter()
    pso = run_pso(problem, spec, settings, on_iteration, space)
    if refine_result:
        ref = refine(pso.x, problem, spec, variable_bounds(problem, spec) if space is None else space.pinned())
        x, method, terms, tol = ref.x, ref.method, ref.terms, REFINE_TOL_M
    else:
        x, method, tol = pso.x, "none", PSO_TOL_M
        terms = CostModel(replace(problem, model="dh"), spec)(BookAngles.from_vector(x, problem.support))
    angles = BookAngles.from_vector(x, problem.support)
    reached, message = _verdict(terms, tol)
    points = forward(angles, spec, "dh", full_com=True)
    lumped, full = points.com[:, 0].copy(), points.full()[:, 0].copy()
    book_rect = replace(problem, com_model=COM_MODEL_LUMPED).extents(spec)
    sole_rect = replace(problem, com_model=COM_MODEL_FULL).extents(spec)
    return PostureResult(
        problem, settings, angles, terms, pso, method, time.perf_counter() - t0, reached, message, tol,
        com_lumped=lumped, margin_lumped_m=float(rectangle_margin(lumped[0:1], lumped[1:2], book_rect)[0]),
        com_full=full, margin_full_m=float(rectangle_margin(full[0:1], full[1:2], sole_rect)[0]),
        left_hand=points.point("left_hand")[0].copy(), right_hand=points.point("right_hand")[0].copy())
