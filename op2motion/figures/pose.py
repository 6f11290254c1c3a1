"""The figures users see, assembled from reports, physics verdicts and solves (the drawing is :mod:`.plot`).

``pose_figure`` draws one pose on one or both kinematic models with its title block: the pose and support, both
centres of mass with their margins, the hand and swing-foot numbers, and the physics verdict (run now, or recorded
in the pose file's metrics, or "not checked"). ``outcome_pose_figure`` and ``outcome_cost_curve`` draw what
``optimize`` writes: the pose and the cost curves of every attempt.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Mapping, Sequence

import numpy as np

from op2motion.figures.draw import PoseCanvas, PoseFigure, TitleBlock, render_cost_curve
from op2motion.kinematics import ModelName, forward
from op2motion.kinematics.report import PoseReport, pose_report
from op2motion.physics import RunReport
from op2motion.robot.joints import BookAngles
from op2motion.robot.spec import Spec
from op2motion.workflow import Outcome

PB_PSI_NOTE = "projection model drawn with psi = 0 (it has no transverse rotation)"


def verdict_of(validation: RunReport | None, metrics: Mapping[str, Any] | None = None) -> tuple[str, bool | None]:
    """The verdict line and its sense: from a validation run now, else from a pose file's recorded metrics."""
    if validation is not None:
        return (f"STANDS in physics ({validation.seconds:g} s)" if validation.stable
                else f"FALLS in physics: {validation.reason}"), validation.stable
    if metrics and metrics.get("validated"):
        stable = bool(metrics.get("stable"))
        why = metrics.get("validation_reason", "")
        return (("STANDS in physics (recorded)" if stable else f"FALLS in physics (recorded): {why}"), stable)
    return "not checked in physics", None


def _numbers(report: PoseReport, double: bool = False) -> list[str]:
    def mm(v: float) -> str:
        return f"{v * 1000:+6.1f} mm"

    com, full = report.com, report.com_full
    if double:
        return [f"CoM lumped (book)  ({com[0]:+.3f}, {com[1]:+.3f}, {com[2]:.3f}) m",
                f"CoM full inertia   ({full[0]:+.3f}, {full[1]:+.3f}, {full[2]:.3f}) m   margin "
                f"{mm(report.double_support_margin_m)}   (to the hull of both soles)"]
    return [f"CoM lumped (book)  ({com[0]:+.3f}, {com[1]:+.3f}, {com[2]:.3f}) m   margin "
            f"{mm(report.stability_margin_m)}",
            f"CoM full inertia   ({full[0]:+.3f}, {full[1]:+.3f}, {full[2]:.3f}) m   margin "
            f"{mm(report.stability_margin_full_m)}   (to the support rectangle shrunk by br {report.br:g})",
            f"swing foot lowest corner {mm(report.swing_foot_min_z)}"]


@dataclass(frozen=True)
class Drawing:
    """What a pose figure shows besides the pose: one row per kinematic model (``dh``, ``pb``), the support
    rectangle shrunk by ``br``, a ``target`` [m], lines of text, a ``ghost`` pose drawn faintly (e.g. before an arm
    IK move), and ``double``: the pose measured as standing on both feet (the support polygon is the hull of both
    soles; the kinematic chain still starts at the book angles' support sole)."""

    models: Sequence[ModelName] = ("dh",)
    br: float = 1.0
    target: Sequence[float] | None = None
    lines: Sequence[str] = ()
    ghost: BookAngles | None = None
    double: bool = False


MODEL_LABELS = {"dh": "D-H model", "pb": "projection model"}


def pose_canvas(name: str, angles: BookAngles, spec: Spec, drawing: Drawing = Drawing()
                ) -> tuple[PoseCanvas, list[PoseReport]]:
    """One pose drawn (see :class:`Drawing`) but for its physics verdict (:meth:`.PoseCanvas.finish`), and its pose
    reports."""
    br, target, ghost, double = drawing.br, drawing.target, drawing.ghost, drawing.double
    rows, reports = [], []
    for model in drawing.models:
        note, shown = "", angles
        if model == "pb" and np.any(angles.psi != 0.0):
            note, shown = PB_PSI_NOTE, replace(angles, psi=np.zeros_like(angles.psi))
        report = pose_report(shown, spec, model, br)
        reports.append(report)
        label = MODEL_LABELS[model]
        rows.append(PoseFigure(report.points, label, report.com, report.com_full, br, target,
                               None if ghost is None else forward(ghost, spec, model), note, double))
    support = "double" if double else angles.support
    margins = ({"margin_full_double_m": reports[0].double_support_margin_m} if double else
               {"margin_lumped_m": reports[0].stability_margin_m, "margin_full_m": reports[0].stability_margin_full_m})
    others = [f"{MODEL_LABELS[r.model]}: CoM lumped ({r.com[0]:+.3f}, {r.com[1]:+.3f}, {r.com[2]:.3f}) m"
              + ("" if double else f"   margin {r.stability_margin_m * 1000:+6.1f} mm") for r in reports[1:]]
    first = [f"{MODEL_LABELS[reports[0].model]}:"] if len(reports) > 1 else []
    block = TitleBlock(f"{name}: {spec.name}, {support} support",
                       [*drawing.lines, *first, *_numbers(reports[0], double), *others], extra=margins)
    return PoseCanvas(rows, spec, block), reports


@dataclass(frozen=True)
class DrawnPose:
    """One pose's figure: the ``png`` bytes, what was ``drawn`` (its rows and verdict, JSON-ready) and the pose
    ``reports`` of each model drawn."""

    png: bytes
    drawn: dict[str, Any]
    reports: list[PoseReport]


def pose_figure(name: str, angles: BookAngles, spec: Spec, drawing: Drawing = Drawing(),
                validation: RunReport | None = None, metrics: Mapping[str, Any] | None = None) -> DrawnPose:
    """The figure of one pose (see :class:`Drawing`); the verdict comes from ``validation`` (a physics run now) or
    from a pose file's recorded ``metrics``."""
    canvas, reports = pose_canvas(name, angles, spec, drawing)
    png, drawn = canvas.finish(*verdict_of(validation, metrics))
    return DrawnPose(png, drawn, reports)


def _outcome_drawing(outcome: Outcome) -> Drawing:
    """What the pose figure of an ``optimize`` outcome shows besides the pose."""
    r = outcome.result
    p = r.problem
    lines = [f"{p.hand} hand to ({', '.join(f'{v:.3f}' for v in p.target)}) m: {r.message}",
             f"torso tilt {np.degrees(r.terms.tilt[0]):.0f}°, PSO seed {r.settings.seed} (attempt {r.attempts}), "
             f"refinement {r.method}"]
    return Drawing(br=p.br, target=p.target, lines=lines)


def _pose_key(outcome: Outcome) -> tuple[object, ...]:
    """Everything the pose figure of an outcome shows but the physics verdict."""
    a, d = outcome.result.angles, _outcome_drawing(outcome)
    return (a.th.tobytes(), a.phi.tobytes(), a.psi.tobytes(), str(a.support), d.br, tuple(d.target or ()),
            tuple(d.lines))


class StagedPoseFigure:
    """The pose figure of an ``optimize`` outcome in two steps: drawn when the pose is known (``outcome``: the
    candidate, before its physics check), finished with the verdict of the final outcome (:meth:`finish`); drawn
    again if the final outcome shows anything else (another pose after a fall, another attempt count)."""

    def __init__(self, outcome: Outcome, name: str, spec: Spec):
        self.name, self.spec, self.key = name, spec, _pose_key(outcome)
        self.canvas, _ = pose_canvas(name, outcome.result.angles, spec, _outcome_drawing(outcome))

    def finish(self, outcome: Outcome) -> tuple[bytes, dict[str, Any]]:
        """PNG bytes of ``outcome``'s pose figure and the report of what was drawn."""
        if _pose_key(outcome) != self.key:
            self.canvas.close()
            return StagedPoseFigure(outcome, self.name, self.spec).finish(outcome)
        return self.canvas.finish(*verdict_of(outcome.validation))


def outcome_pose_figure(outcome: Outcome, name: str, spec: Spec) -> tuple[bytes, dict[str, Any]]:
    """PNG bytes of the pose figure of an ``optimize`` outcome and the report of what was drawn."""
    return StagedPoseFigure(outcome, name, spec).finish(outcome)


#: :func:`.render_cost_curve`'s arguments: each attempt's costs and hand errors, the threshold [m], the title, the
#: kept attempt, and (final cost, hand error [m], method).
_CostCurveArgs = tuple[list[np.ndarray], list[np.ndarray], float, str, int, tuple[float, float, str]]


def _cost_curve_args(outcome: Outcome, name: str) -> _CostCurveArgs:
    """What :func:`.render_cost_curve` is given for an ``optimize`` outcome (every attempt)."""
    r = outcome.result
    attempts = r.attempt_pso or (r.pso,)
    return ([a.history for a in attempts], [a.hand_error_history for a in attempts], r.tolerance_m,
            f"PSO cost, {name} ({len(attempts)} attempt(s))", r.chosen_attempt,
            (float(r.terms.total[0]), r.hand_error_m, r.method))


def _cost_key(outcome: Outcome, name: str) -> tuple[object, ...]:
    histories, errors, *rest = _cost_curve_args(outcome, name)
    return (tuple(np.asarray(h).tobytes() for h in histories), tuple(np.asarray(e).tobytes() for e in errors),
            *rest)


def outcome_cost_curve(outcome: Outcome, name: str) -> bytes:
    """PNG bytes of the PSO cost curves of an ``optimize`` outcome (every attempt)."""
    return render_cost_curve(*_cost_curve_args(outcome, name))


class StagedCostCurve:
    """The cost curves of an ``optimize`` outcome drawn for its candidate (before the physics check, which they do
    not show); :meth:`finish` hands them over, or draws them again if the final outcome has others (attempts after
    a fall)."""

    def __init__(self, outcome: Outcome, name: str):
        self.name, self.key, self.png = name, _cost_key(outcome, name), outcome_cost_curve(outcome, name)

    def finish(self, outcome: Outcome) -> bytes:
        """PNG bytes of ``outcome``'s cost curves."""
        return self.png if _cost_key(outcome, self.name) == self.key else outcome_cost_curve(outcome, self.name)
