"""One posture solve: PSO, refinement, verdict and the pose (the library function behind ``op2motion optimize``)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from ..balance import COM_MODEL_LUMPED, stability_margin
from ..export.library import Pose
from ..joints import BookAngles, book_to_servo
from ..kinematics import forward
from ..model.dynamics import COM_MODEL_FULL, dynamics_for
from ..spec import Spec
from .cost import CostTerms, PostureProblem
from .pso import PSOResult, PSOSettings, run_pso, variable_bounds
from .refine import REFINE_TOL_M, feasible, refine

PSO_TOL_M = 5e-3   # without refinement a hand within 5 mm counts as reaching


@dataclass(frozen=True)
class PostureResult:
    """Outcome of :func:`optimize_posture`. ``terms`` are evaluated on the D-H model (true geometry)."""

    problem: PostureProblem
    settings: PSOSettings
    angles: BookAngles
    terms: CostTerms
    pso: PSOResult
    method: str
    seconds: float
    reached: bool
    message: str
    metrics: dict = field(default_factory=dict)

    def pose(self, name: str, spec: Spec, provenance: dict[str, Any] | None = None) -> Pose:
        """The solution as a pose (support = the problem's support foot)."""
        p = self.problem
        prov = {"target_m": list(p.target), "hand": p.hand, "br": p.br, "model": p.model, "seed": self.settings.seed,
                "particles": self.settings.particles, "iterations": self.settings.iterations, "refinement": self.method,
                **(provenance or {})}
        return Pose.from_book(name, self.angles, spec, metrics=self.metrics, provenance=prov)


def optimize_posture(problem: PostureProblem, spec: Spec, settings: PSOSettings = PSOSettings(),
                     refine_result: bool = True, on_iteration: Callable[[float], Any] | None = None,
                     restarts: int = 0, check: Callable[[PostureResult], tuple[bool, str]] | None = None
                     ) -> PostureResult:
    """Find a balanced whole-body pose that puts ``problem.hand`` on ``problem.target``.

    A swarm can settle on the edge of the stability region where refinement stalls, or on a pose the model calls
    balanced but ``check`` (e.g. the physics validation) rejects; ``restarts`` further solves with the next seeds
    are tried until one passes. The best attempt is returned (passing first, then reached, then residual).
    """
    t0 = time.perf_counter()

    def attempt(seed: int) -> PostureResult:
        res = _solve_once(problem, spec, replace(settings, seed=seed), refine_result, on_iteration)
        if res.reached and check is not None:
            ok, why = check(res)
            if not ok:
                res = replace(res, reached=False, message=f"reached, but {why}")
        return res

    best = attempt(settings.seed)
    k = 0
    while not best.reached and k < restarts:
        k += 1
        candidate = attempt(settings.seed + k)
        if _rank(candidate) > _rank(best):
            best = candidate
    return replace(best, seconds=time.perf_counter() - t0, metrics={**best.metrics, "attempts": k + 1})


def _rank(result: PostureResult) -> tuple[bool, bool, float]:
    """Order of preference among attempts: reached, then feasible, then the smaller hand residual."""
    return result.reached, feasible(result.terms), -float(result.terms.hand_error[0])


def _solve_once(problem: PostureProblem, spec: Spec, settings: PSOSettings, refine_result: bool,
                on_iteration: Callable[[float], Any] | None) -> PostureResult:
    t0 = time.perf_counter()
    pso = run_pso(problem, spec, settings, on_iteration)
    bounds = variable_bounds(problem, spec)
    if refine_result:
        ref = refine(pso.x, problem, spec, bounds)
        x, method, terms, tol = ref.x, ref.method, ref.terms, REFINE_TOL_M
    else:
        from .cost import CostModel

        x, method, tol = pso.x, "none", PSO_TOL_M
        terms = CostModel(PostureProblem(problem.support, problem.hand, problem.target, problem.br, "dh"), spec)(
            BookAngles.from_vector(x, problem.support))
    angles = BookAngles.from_vector(x, problem.support)
    reached = bool(terms.hand_error[0] <= tol and feasible(terms))
    if reached:
        message = f"reached: hand {terms.hand_error[0] * 1000:.2f} mm from the target"
    elif not feasible(terms):
        why = ("the CoM leaves the support rectangle" if terms.margin[0] < 0 else
               "the swing foot goes below the floor" if terms.swing_min_z[0] < 0 else "the pose collides with itself")
        message = f"infeasible: {why} (best hand residual {terms.hand_error[0] * 1000:.1f} mm)"
    else:
        message = f"unreachable: best hand residual {terms.hand_error[0] * 1000:.1f} mm (tolerance {tol * 1000:.0f} mm)"
    points = forward(angles, spec, "dh")
    full = dynamics_for(spec).com(book_to_servo(angles, spec)[0], problem.support)
    metrics = {
        "com_full": [float(v) for v in full], "com_full_model": COM_MODEL_FULL,
        "stability_margin_full_m": float(stability_margin(full[None, :2], spec, problem.support, problem.br)[0]),
        "com": [float(v) for v in points.com[:, 0]], "com_model": COM_MODEL_LUMPED,
        "left_hand": [float(v) for v in points.point("left_hand")[0]],
        "right_hand": [float(v) for v in points.point("right_hand")[0]],
        "target": list(problem.target), "hand_error_m": float(terms.hand_error[0]),
        "stability_margin_m": float(terms.margin[0]), "br": problem.br,
        "swing_foot_min_z": float(terms.swing_min_z[0]), "torso_tilt_deg": float(np.degrees(terms.tilt[0])),
        "cost": float(terms.total[0]), "pso_cost": pso.cost,
    }
    return PostureResult(problem, settings, angles, terms, pso, method, time.perf_counter() - t0, reached, message,
                         metrics)
