"""The posture workflow: solve -> (validate in physics) -> write, shared by ``optimize`` and ``library build``.

One function decides what a solve is: PSO + refinement on the D-H model, retried on the next seeds (``restarts``)
when a seed does not reach the target or, with ``validate``, when the reached pose does not stand in physics; so
both commands retry the same way, simulate for the same time, and never write a pose that falls when validation
was asked for. :class:`Outcome` is the typed result (its figures: :mod:`op2motion.figures.pose`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import Any, Callable

from op2motion.errors import ref
from op2motion.jsonout import JsonObject
from op2motion.physics import DEFAULT_SECONDS, EngineName, RunReport, Schedule, check
from op2motion.posture.cost import PostureProblem
from op2motion.posture.pso import PSOSettings
from op2motion.posture.solve import PostureResult, optimize_posture
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec

DEFAULT_RESTARTS = 2     # extra solves with the next seeds when one fails
MAX_RESTARTS = 100


@dataclass(frozen=True)
class Outcome:
    """A solve and, when asked for, the physics validation of its pose. ``ok`` is true when the target was reached
    (and, with validation, the pose stands); ``message`` says why not otherwise."""

    result: PostureResult
    validation: RunReport | None

    @property
    def ok(self) -> bool:
        """Reached, feasible and (when validated) standing."""
        return self.result.reached

    @property
    def message(self) -> str:
        """The verdict in words."""
        return self.result.message

    def pose(self, name: str, spec: Spec, provenance: dict[str, Any] | None = None) -> Pose:
        """The solved pose, with the validation verdict in its metrics when there is one."""
        pose = self.result.pose(name, spec, provenance)
        if self.validation is None:
            return pose
        metrics = {**pose.metrics, "validated": True, "stable": self.validation.stable,
                   "validation_reason": self.validation.reason}
        return Pose(pose.name, pose.support, pose.servo, metrics, pose.provenance)

    def warnings(self) -> list[str]:
        """What a user should know before trusting an unvalidated pose."""
        r = self.result
        if self.validation is None and r.reached and r.margin_full_m < 0:
            return [f"the full-inertia CoM is {-r.margin_full_m * 1000:.1f} mm outside the support rectangle (br "
                    f"{r.problem.br:g}): the pose is likely to fall; check it in physics ({ref('validate')})"]
        return []

    def as_dict(self) -> JsonObject:
        """JSON-ready: the metrics, the verdict and the validation."""
        r = self.result
        out = {"reached": r.reached, "message": r.message, **r.as_dict(), "iterations": int(len(r.pso.history)),
               "refinement": r.method, "seconds": round(r.seconds, 3), "seed": r.settings.seed}
        if self.validation is not None:
            out["validation"] = {**self.validation.as_dict(), "pushes": []}     # the validate keys (never pushed)
        return out


@dataclass(frozen=True)
class Validate:
    """The physics check of each reached pose: held ``seconds`` [s] in ``engine``."""

    seconds: float = DEFAULT_SECONDS
    engine: EngineName = "pybullet"


def solve(problem: PostureProblem, spec: Spec, settings: PSOSettings = PSOSettings(), *,
          restarts: int = DEFAULT_RESTARTS, refine: bool = True, validate: Validate | None = None,
          on_iteration: Callable[[float], Any] | None = None,
          on_check: Callable[[Outcome], Any] | None = None) -> Outcome:
    """Solve ``problem`` (see the module docstring); with ``validate``, every reached pose is checked in
    physics and one that falls counts as not reached. ``on_check`` is given, as the first physics check starts,
    the outcome as it will be if that pose stands (without its validation), e.g. to draw its figures meanwhile."""
    validations: dict[int, RunReport] = {}

    def physics_check(res: PostureResult, validate: Validate) -> tuple[bool, str]:
        if on_check is not None and not validations:        # the first attempt's pose, kept if it stands
            on_check(Outcome(replace(res, attempts=1, attempt_pso=(res.pso,)), None))
        schedule = Schedule.hold(res.pose("candidate", spec).servo, problem.support, spec, validate.seconds)
        v = check(schedule, spec, engines=(validate.engine,)).run
        validations[res.settings.seed] = v
        return v.stable, f"does not stand in physics ({', '.join(v.reasons)})"

    res = optimize_posture(problem, spec, settings, refine, on_iteration, restarts,
                           None if validate is None else partial(physics_check, validate=validate))
    return Outcome(res, validations.get(res.settings.seed))

