"""The kinematics tasks: forward kinematics and balance of one pose (``fk``), book variables ↔ servo angles ↔
ticks (``convert``), a pose's stick figure with its verdict (``plot``) and the book's arm IK (``arm-ik``), each
returning a :class:`~.result.TaskResult`; an arm IK that misses its target or leaves a servo's range is a "no".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.figures.pose import DrawnPose
    from op2motion.kinematics.arm_ik import ArmIKResult
    from op2motion.kinematics.points import ModelName
    from op2motion.kinematics.report import PoseReport
    from op2motion.robot.joints import BookAngles
    from op2motion.robot.pose import Pose
    from op2motion.robot.support import Side


def fk(angles: BookAngles, spec: Spec, model: ModelName = "dh", br: float = 1.0,
       sole: tuple[float, float, float] = (0.0, 0.0, 0.0), heading_rad: float = 0.0, double: bool = False
       ) -> TaskResult[PoseReport]:
    """``fk``: every body point, both CoMs and the balance of ``angles`` on ``model``, the support sole at ``sole``
    [m] turned by ``heading_rad``; ``double``: measured on both feet."""
    from op2motion.kinematics.report import pose_report

    report = pose_report(angles, spec, model, br, sole, heading_rad, double)
    return TaskResult(True, data=report.as_dict(spec), lines=(report.human(),), value=report)


def convert(angles: BookAngles, servo: Any, spec: Spec) -> TaskResult[BookAngles]:
    """``convert``: one pose as book variables (``angles``), servo angles (``servo`` (20,) [rad]) and ticks."""
    from op2motion.robot.joints import servo_to_ticks

    ticks = servo_to_ticks(servo, spec)
    names = spec.joint_names
    data: JsonObject = {"support": angles.support,
            "servo_deg": {n: float(math.degrees(q)) for n, q in zip(names, servo)},
            "servo_rad": {n: float(q) for n, q in zip(names, servo)},
            "ticks": {str(j.id): int(t) for j, t in zip(spec.joints, ticks)},
            **angles.degrees()}
    lines = [f"{'id':>3} {'joint':<12} {'servo deg':>10} {'tick':>5}"]
    lines += [f"{j.id:>3} {j.name:<12} {math.degrees(q):>10.3f} {t:>5}" for j, q, t in zip(spec.joints, servo, ticks)]
    b = angles.degrees()
    lines.append(f"book ({angles.support} support): th {b['th']}, phi {b['phi']}, psi {b['psi']} [deg]")
    return TaskResult(True, data=data, lines=("\n".join(lines),), value=angles)


@dataclass(frozen=True)
class PlotRequest:
    """A pose's figure: its ``name`` and ``angles`` (and the ``pose`` file it came from, if any: its support, servo
    angles and recorded metrics), the ``models`` drawn, the boundary ratio ``br``, a ``target`` [m] to mark,
    ``validate_s``: check it in physics for this long [s] first (None: do not), and where it goes (``output``)."""

    name: str
    angles: BookAngles
    output: Path
    pose: Pose | None = None
    models: tuple[ModelName, ...] = ("dh",)
    br: float = 1.0
    target: tuple[float, float, float] | None = None
    validate_s: float | None = None


def plot(request: PlotRequest, spec: Spec) -> TaskResult[DrawnPose]:
    """``plot``: the stick figure (front, side, top, 3D), both CoMs, the support drawn, the verdict (checked now, or
    as the pose file records it)."""
    from op2motion.figures.pose import PB_PSI_NOTE, Drawing, pose_figure
    from op2motion.robot.joints import book_to_servo
    from op2motion.robot.support import Support

    pose, angles = request.pose, request.angles
    support = pose.support if pose is not None else angles.support
    validation = None
    if request.validate_s is not None:
        from op2motion.physics import Schedule, check

        servo = pose.servo if pose is not None else book_to_servo(angles, spec)[0]
        validation = check(Schedule.hold(servo, support, spec, request.validate_s), spec).run
    drawing = Drawing(request.models, request.br, request.target, double=Support.of(support).is_double)
    figure = pose_figure(request.name, angles, spec, drawing, validation, None if pose is None else pose.metrics)
    png, drawn, reports = figure.png, figure.drawn, figure.reports
    data: JsonObject = {"support": support, "drawn": drawn,
            "models": {r.model: {k: r.as_dict(spec)[k] for k in (
                "com", "stability_margin_m", "com_full", "stability_margin_full_m", "left_hand", "right_hand",
                "swing_foot_min_z")} for r in reports}}
    notes = [f"note: {PB_PSI_NOTE}"] if any(row["note"] for row in drawn["rows"]) else []
    text = ("\n\n".join(r.human() for r in reports) + "\n" + "\n".join(notes)
            + f"\n{drawn['verdict']}\nwrote {request.output}")
    return TaskResult(True, None, None, {"output": Output(str(request.output), png, key="png")}, data, (text,),
                      value=figure)


@dataclass(frozen=True)
class ArmMove:
    """An arm IK request: move ``hand`` by ``delta_m`` (3,) [m] (world frame) from ``angles`` (named ``name``) on
    ``model``, the book's single Taylor step or iterated to ``tol_mm`` [mm], refusing a result outside the servo
    limits unless ``allow_limits``; the figure of the move to ``plot`` (None: none)."""

    name: str
    angles: BookAngles
    hand: Side
    delta_m: tuple[float, float, float]
    model: ModelName = "pb"
    single_step: bool = False
    tol_mm: float = 0.1
    allow_limits: bool = False
    plot: str | None = None


def arm_ik(request: ArmMove, spec: Spec) -> TaskResult[ArmIKResult]:
    """``arm-ik``: the hand moved with its arm's three joints (the book's Taylor-linearised IK); a "no" when the
    result leaves a servo's cable-safe range (unless allowed) or misses the target beyond the tolerance."""
    from op2motion.figures.pose import Drawing, pose_figure
    from op2motion.kinematics.arm_ik import ARMS, solve_arm_ik
    from op2motion.kinematics.report import pose_report
    from op2motion.robot.joints import book_to_servo, servo_dict

    tol = request.tol_mm / 1000.0
    res = solve_arm_ik(request.angles, request.hand, request.delta_m, spec, request.model,
                       single_step=request.single_step, tol=tol, enforce_limits=not request.allow_limits)
    arm = ARMS[request.hand]
    converged = res.mode == "single-step" or res.error_m <= tol
    data: JsonObject = {"hand": request.hand, "model": res.model, "mode": res.mode, "iterations": res.iterations,
            "joint_deltas_deg": {n: float(math.degrees(v)) for n, v in zip(arm.names, res.deltas)},
            **res.angles.degrees(),
            "requested_delta": [float(v) for v in res.requested],
            "achieved_delta": [float(v) for v in res.achieved],
            "error_m": res.error_m, "converged": converged,
            "servo_deg": servo_dict(book_to_servo(res.angles, spec)[0], spec),
            "limit_violations": [v.as_dict() for v in res.limit_violations]}
    deltas = ", ".join(f"d{n} = {math.degrees(v):+.2f}°" for n, v in zip(arm.names, res.deltas))
    text = (f"{res.mode} on the {res.model.upper()} model, {res.iterations} iteration(s): {deltas}\n"
            f"hand moved {', '.join(f'{v * 1000:+.2f}' for v in res.achieved)} mm "
            f"(asked {', '.join(f'{v * 1000:+.2f}' for v in res.requested)} mm), error {res.error_m * 1000:.3f} mm")
    problem = None
    if res.limit_violations and not request.allow_limits:
        problem = f"refused: {res.limit_violations[0].describe()}; pass --allow-limits to accept"
    elif not converged:
        problem = (f"target not reached: best residual {res.error_m * 1000:.3f} mm (tolerance "
                   f"{request.tol_mm} mm); it lies outside what this arm can reach on the "
                   f"{res.model.upper()} model")
    outputs = {}
    if request.plot and problem is None:
        start = pose_report(res.initial, spec, res.model)
        target = start.points.point(arm.hand)[0] + res.requested
        lines = [f"{request.hand} hand moved by ({', '.join(f'{v * 1000:+.1f}' for v in res.requested)}) mm with "
                 f"{res.mode} arm IK: {deltas}; error {res.error_m * 1000:.3f} mm"]
        drawing = Drawing((res.model,), target=target, lines=lines, ghost=res.initial)
        png = pose_figure(f"{request.name} + arm IK", res.angles, spec, drawing).png
        outputs["plot"] = Output(request.plot, png, key="png")
    return TaskResult(problem is None, problem, None, outputs, data, (text,), value=res)
