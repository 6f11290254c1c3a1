"""The validate task: does a pose stand? Held by the MX-28 servo model in one engine or both (compared), optionally
pushed, on softer or stiffer servos, at another supply voltage; or held on every member of the robustness family.
Each returns a :class:`~.result.TaskResult` (a pose that falls is a "no" with its reasons, not an exception).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from op2motion.jsonout import JsonObject
from op2motion.physics import DEFAULT_SECONDS
from op2motion.robot.spec import Spec
from op2motion.tasks.progress import Progress
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.physics import CheckReport, EngineName, RobustReport
    from op2motion.robot.pose import Pose



@dataclass(frozen=True)
class Validation:
    """How a pose is held: ``seconds`` [s] of simulated time in ``engines`` (two: compared), a push of ``push_n``
    [N] in four directions when above 0, the servos' stiffness times ``stiffness``, the supply ``voltage`` [V]
    (None: the spec's), and a snapshot of the final state written to ``snapshot_png`` when it names a file."""

    seconds: float = DEFAULT_SECONDS
    engines: tuple[EngineName, ...] = ("pybullet",)
    push_n: float = 0.0
    stiffness: float = 1.0
    voltage: float | None = None
    snapshot_png: str | None = None


def _pushes_line(pushes: Any) -> str:
    if not pushes:
        return ""
    return "\n  pushes: " + "; ".join(f"{p.force_n:g} N {p.direction}: {'ok' if p.stable else ', '.join(p.reasons)}"
                                     for p in pushes)


def validate_pose(pose: Pose, spec: Spec, how: Validation = Validation(),
                  on_progress: Progress | None = None) -> TaskResult[CheckReport]:
    """``validate``: ``pose`` held as ``how`` says; its report per engine (one engine: its keys and the static model's
    torques; two: both, and whether they agree)."""
    from op2motion.model.dynamics import dynamics_for
    from op2motion.physics import Pushes, Schedule, Setup, check

    schedule = Schedule.hold(pose.servo, pose.support, spec, how.seconds)
    report = check(schedule, spec, how.engines, Pushes(how.push_n) if how.push_n else None,
                   setup=Setup(how.stiffness, how.voltage, snapshot=bool(how.snapshot_png)), on_progress=on_progress)
    static = dynamics_for(spec).static_torques(pose.servo, pose.support)
    head = {"pose": pose.name, "support": pose.support}
    if len(report.engines) > 1:
        data: dict[str, Any] = {**head, "engine": "both", "agree": report.agree, "stable": report.stable,
                                "engines": {e: r.as_dict() for e, r in report.engines.items()}}
    else:
        data = {**report.first.as_dict(), **head,
                "static_torque_nm": {n: float(x) for n, x in zip(spec.joint_names, static.torques)},
                "static_worst_joint": static.worst_joint, "static_worst_ratio": round(static.worst_ratio, 4)}
    outputs = {}
    if how.snapshot_png and report.run.snapshot_png is not None:
        outputs["gui_png"] = Output(how.snapshot_png, report.run.snapshot_png, key="png")
    lines = [f"{pose.name} ({pose.support} support): {e.run.summary()}" + _pushes_line(e.pushes)
             for e in report.engines.values()]
    lines.append(f"  static model (pinocchio): {abs(static.worst_torque_nm):.2f} N·m at {static.worst_joint}")
    if len(report.engines) > 1:
        lines.append("  the engines agree" if report.agree else "  THE ENGINES DISAGREE")
    problem = report.problem()
    return TaskResult(problem is None, None if problem is None else f"{pose.name}: {problem}", None, outputs, data,
                      tuple(lines), value=report)


def validate_pose_robust(pose: Pose, spec: Spec, how: Validation = Validation(),
                         on_progress: Progress | None = None) -> TaskResult[RobustReport]:
    """``validate --robust``: ``pose`` held on every member of the robustness family (its stiffness and floor set
    by the member: ``how.stiffness`` and a snapshot are bad input here); the table."""
    from op2motion.errors import InputError
    from op2motion.physics import Pushes, Schedule, pose_robust_table, robust_check, robust_summary

    if how.stiffness != 1.0 or how.snapshot_png:
        raise InputError("expected --robust without --stiffness or --gui-png (the family sets the stiffness)",
                         "robust")
    report = robust_check(lambda: Schedule.hold(pose.servo, pose.support, spec, how.seconds), spec, how.engines,
                          pushes=Pushes(how.push_n) if how.push_n else None, on_progress=on_progress)
    data: JsonObject = {"pose": pose.name, "support": pose.support, "robust": robust_summary(report)}
    lines = (f"{pose.name} ({pose.support} support) across the robustness family:\n" + pose_robust_table(report),)
    failed = sum(not r.passed for r in report.runs)
    problem = None if report.passed else (
        f"{pose.name}: fails in {failed} of {len(report.runs)} runs of the robustness family")
    return TaskResult(report.passed, problem, None, {}, data, lines, value=report)
