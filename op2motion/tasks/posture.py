"""The reach task (``optimize``): a balanced whole-body pose that reaches a hand target, solved by the posture
workflow (:func:`op2motion.workflow.solve`: PSO, refinement, restarts, physics when asked) and returned as a
:class:`~.result.TaskResult`: the pose file, its figure and the cost curve as outputs when the target was reached
(and, validated, the pose stands); the phrase why not otherwise.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

from op2motion.robot.spec import Spec
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.figures.background import Renderers
    from op2motion.posture.cost import PostureProblem
    from op2motion.posture.pso import PSOSettings
    from op2motion.workflow import Outcome, Validate


@dataclass(frozen=True)
class Reach:
    """A reach request: the ``problem`` and the swarm's ``settings``, ``restarts`` on the next seeds, ``refine``
    (the arm IK after the swarm), ``validate`` (the physics check of each reached pose; None: none), the pose's
    ``name``, the ``command`` recorded in its provenance, and where its pose file, figure and cost curve go
    (``pose_path``, ``figure_path``, ``cost_path``)."""

    problem: PostureProblem
    settings: PSOSettings
    name: str
    pose_path: str
    figure_path: str
    cost_path: str
    restarts: int = 2
    refine: bool = True
    validate: Validate | None = None
    command: str = "op2motion optimize"


def _lines(request: Reach, outcome: Any, tilt_deg: float) -> list[str]:
    """The result for a person: the verdict, the balance, the search; physics when it ran."""
    p, r, s = request.problem, outcome.result, request.settings
    lines = [f"{p.hand} hand to ({', '.join(f'{v:.3f}' for v in p.target)}) m on the {p.support} foot, "
             f"br {p.br}: {r.message}",
             f"  CoM full inertia ({r.com_full[0]:+.3f}, {r.com_full[1]:+.3f}, {r.com_full[2]:.3f}) m, margin "
             f"{r.margin_full_m * 1000:.1f} mm to the sole shrunk by br; lumped (book) margin "
             f"{r.margin_lumped_m * 1000:.1f} mm [balanced: {p.com_model}]; "
             f"swing foot {r.swing_foot_min_z * 1000:.1f} mm above the floor, torso tilt {tilt_deg:.0f}°",
             f"  PSO {s.particles} particles x {s.iterations} iterations (seed {r.settings.seed}, "
             f"attempt {r.attempts}), refinement: {r.method}, {r.seconds:.2f} s"]
    if outcome.validation is not None:
        lines.append(f"  physics: {outcome.validation.summary()}")
    return lines


def reach(request: Reach, spec: Spec, renderers: Renderers | None = None,
          on_iteration: Callable[[float], Any] | None = None,
          on_answer: Callable[[tuple[str, ...]], Any] | None = None) -> TaskResult[Outcome]:
    """``optimize``: solve ``request`` (see the module docstring); the figures drawn by ``renderers`` (forked
    renderers, started before the search so that they are ready when it ends; with ``validate``, they draw the
    pose while its physics check runs and add the verdict after) or here. ``on_answer`` is given the result's lines
    of a reached target as soon as they are known, before the figures are finished."""
    from op2motion.figures.pose import (
        StagedCostCurve,
        StagedPoseFigure,
        outcome_cost_curve,
        outcome_pose_figure,
    )
    from op2motion.formats.posefile import pose_to_json
    from op2motion.workflow import solve

    begun: list[int] = []

    def begin_figures(candidate: Any) -> None:
        if renderers is not None:
            begun.extend((renderers.begin(StagedPoseFigure, candidate, request.name, spec),
                          renderers.begin(StagedCostCurve, candidate, request.name)))

    outcome = solve(request.problem, spec, request.settings, restarts=request.restarts, refine=request.refine,
                    validate=request.validate, on_iteration=on_iteration, on_check=begin_figures)
    pose = outcome.pose(request.name, spec, {"command": request.command})
    data: dict[str, Any] = {"pose": json.loads(pose_to_json(pose, spec)), **outcome.as_dict()}
    lines = _lines(request, outcome, data["torso_tilt_deg"])
    warnings = tuple(outcome.warnings())
    if not outcome.ok:
        return TaskResult(False, f"{outcome.result.message}; nothing written", warnings, {}, data, tuple(lines),
                          value=outcome)
    if renderers is not None:
        jobs = begun or [renderers.begin(StagedPoseFigure, outcome, request.name, spec),
                         renderers.begin(StagedCostCurve, outcome, request.name)]
        for job in jobs:
            renderers.finish(job, outcome)
        if on_answer is not None:
            on_answer(tuple(lines))
        (figure, drawn), cost_curve = renderers.result(jobs[0]), renderers.result(jobs[1])
    else:
        (figure, drawn), cost_curve = (outcome_pose_figure(outcome, request.name, spec),
                                       outcome_cost_curve(outcome, request.name))
    data["figure"] = drawn
    data["files"] = {}
    outputs = {"out": Output(request.pose_path, pose_to_json(pose, spec), "pose"),
               "plot": Output(request.figure_path, figure, "png"),
               "cost curve": Output(request.cost_path, cost_curve, "cost_png")}
    return TaskResult(True, None, warnings, outputs, data, tuple(lines), value=outcome)
