"""CLI commands of the kinematic models: fk, convert, plot, arm-ik."""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

from op2motion.commands.common import (
    BOUNDARY_RATIO,
    DELTA_M,
    HEADING_DEG,
    POSITION_M,
    TARGET_M,
    add_command,
    angles_from,
    book_args,
    emit,
    number,
    png_path,
    vec3,
)
from op2motion.errors import InputError
from op2motion.kinematics import MODELS
from op2motion.physics import DEFAULT_SECONDS, MAX_SECONDS, MIN_SECONDS
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

TOL_MM = number(0.0, 100.0, "mm", open_low=True)
SECONDS = number(MIN_SECONDS, MAX_SECONDS, "s")


def register(sub: Any) -> None:
    """Add fk, convert, plot and arm-ik."""
    p = add_command(sub, "fk", cmd_fk, "full-body forward kinematics and balance of one pose")
    p.add_argument("--model", choices=("dh", "pb"), default="dh", help="D-H (default) or projection model")
    book_args(p)
    p.add_argument("--br", type=BOUNDARY_RATIO, default=1.0,
                   help="boundary ratio of the support rectangle (default 1.0)")
    p.add_argument("--sp", type=POSITION_M, nargs=3, metavar=("X", "Y", "Z"),
                   help="support sole centre [m] (default 0 0 0)")
    p.add_argument("--gamma", type=HEADING_DEG, default=0.0, metavar="DEG", help="heading of the support foot [deg]")

    p = add_command(sub, "convert", cmd_convert, "book variables <-> servo angles <-> Dynamixel ticks")
    book_args(p)
    p.add_argument("--servo-deg", metavar="JSON",
                   help="servo angles {joint: deg} as JSON text, a JSON file, or a pose file")

    p = add_command(sub, "plot", cmd_plot, "stick figure of a pose (front, side, top, 3D) as a PNG")
    p.add_argument("pose_positional", nargs="?", metavar="POSE", help="pose file (default: the standing pose)")
    book_args(p, pose_flag=False)
    p.add_argument("--model", choices=("dh", "pb", "both"), default="dh",
                   help="kinematic model(s) to draw (both: one row each)")
    p.add_argument("--br", type=BOUNDARY_RATIO, default=1.0, help="boundary ratio of the drawn support rectangle")
    p.add_argument("--target", type=TARGET_M, nargs=3, metavar=("X", "Y", "Z"), help="mark a target [m]")
    p.add_argument("-o", "--output", type=png_path, required=True, metavar="PNG", help="where to write the PNG")
    p.add_argument("--validate", action="store_true", help="check the pose in physics and show the verdict")
    p.add_argument("--seconds", type=SECONDS, default=DEFAULT_SECONDS,
                   help=f"simulated time of --validate [s] (default {DEFAULT_SECONDS:g})")

    p = add_command(sub, "arm-ik", cmd_arm_ik, "move one hand by a displacement with the Taylor-linearised arm IK")
    p.add_argument("--hand", choices=("left", "right"), required=True, help="which hand to move")
    p.add_argument("--delta", type=DELTA_M, nargs=3, required=True, metavar=("DX", "DY", "DZ"),
                   help="hand displacement in the world frame [m]")
    book_args(p)
    p.add_argument("--single-step", action="store_true", help="the book's single Taylor step (code 2.15/2.17)")
    p.add_argument("--model", choices=("pb", "dh"), default="pb",
                   help="model to iterate on: pb (book, default) or dh (true geometry, for the real robot)")
    p.add_argument("--tol-mm", type=TOL_MM, default=0.1, help="iterated mode: target tolerance [mm] (default 0.1)")
    p.add_argument("--allow-limits", action="store_true", help="accept a result outside the servo limits")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="draw the initial and the changed pose")


def cmd_fk(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion fk``."""
    from op2motion.kinematics.report import evaluate

    angles, _, pose = angles_from(args, spec)
    sp = vec3(args.sp, "sp") or (0.0, 0.0, 0.0)
    double = pose is not None and Support.of(pose.support).is_double
    report = evaluate(angles, spec, args.model, args.br, sp, math.radians(args.gamma), double)
    emit(args, report.as_dict(spec), report.human())
    return 0


def _servo_mapping(text: str) -> dict:
    """``--servo-deg``: JSON text, a JSON file of {joint: deg}, or a pose file (its ``servo_deg``)."""
    from op2motion.fileio import read_text

    if not text.lstrip().startswith(("{", "[")):
        text = read_text(text, "JSON file", InputError)
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", "servo_deg") from None
    if isinstance(doc, dict) and "servo_deg" in doc and "schema" in doc:   # a pose file
        doc = doc["servo_deg"]
    return doc


def cmd_convert(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion convert``."""
    from op2motion.robot.joints import (
        book_to_servo,
        servo_from_mapping,
        servo_to_book,
        servo_to_ticks,
    )

    if args.servo_deg is not None:
        if args.th is not None or args.phi is not None or args.pose:
            raise InputError("give either --servo-deg, --pose or --th/--phi, not several")
        servo = servo_from_mapping(_servo_mapping(args.servo_deg), spec)
        angles = servo_to_book(servo, args.support, spec)
    else:
        angles, _, _ = angles_from(args, spec)
        servo = book_to_servo(angles, spec)[0]
    ticks = servo_to_ticks(servo, spec)
    names = spec.joint_names
    result = {
        "support": angles.support,
        "servo_deg": {n: float(math.degrees(q)) for n, q in zip(names, servo)},
        "servo_rad": {n: float(q) for n, q in zip(names, servo)},
        "ticks": {str(j.id): int(t) for j, t in zip(spec.joints, ticks)},
        **angles.degrees(),
    }
    lines = [f"{'id':>3} {'joint':<12} {'servo deg':>10} {'tick':>5}"]
    lines += [f"{j.id:>3} {j.name:<12} {math.degrees(q):>10.3f} {t:>5}" for j, q, t in zip(spec.joints, servo, ticks)]
    b = angles.degrees()
    lines.append(f"book ({angles.support} support): th {b['th']}, phi {b['phi']}, psi {b['psi']} [deg]")
    emit(args, result, "\n".join(lines))
    return 0


def cmd_plot(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion plot``: the figure, with the physics verdict when asked (or recorded in the pose file)."""
    from op2motion.figures.pose import PB_PSI_NOTE, Drawing, pose_figure
    from op2motion.fileio import OutputSet
    from op2motion.robot.joints import book_to_servo

    outputs = OutputSet({"output": args.output})
    angles, name, pose = angles_from(args, spec, args.pose_positional, default_standing=True)
    target = vec3(args.target, "target")
    models = MODELS if args.model == "both" else (args.model,)
    support = pose.support if pose is not None else angles.support
    validation = None
    if args.validate:
        from op2motion.physics import Schedule, check

        servo = pose.servo if pose is not None else book_to_servo(angles, spec)[0]
        validation = check(Schedule.hold(servo, support, spec, args.seconds), spec).run
    drawing = Drawing(models, args.br, target, double=Support.of(support).is_double)
    png, drawn, reports = pose_figure(name, angles, spec, drawing, validation, None if pose is None else pose.metrics)
    outputs.put("output", png)
    out = outputs.commit()["output"]
    summary = {"png": str(out), "support": support, "drawn": drawn,
               "models": {r.model: {k: r.as_dict(spec)[k] for k in (
                   "com", "stability_margin_m", "com_full", "stability_margin_full_m", "left_hand", "right_hand",
                   "swing_foot_min_z")} for r in reports}}
    notes = [f"note: {PB_PSI_NOTE}"] if any(row["note"] for row in drawn["rows"]) else []
    emit(args, summary, "\n\n".join(r.human() for r in reports) + "\n" + "\n".join(notes)
         + f"\n{drawn['verdict']}\nwrote {out}")
    return 0


def cmd_arm_ik(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion arm-ik``."""
    from op2motion.errors import CheckFailed, Unreachable
    from op2motion.figures.pose import Drawing, pose_figure
    from op2motion.fileio import OutputSet
    from op2motion.kinematics.arm_ik import ARMS, solve_arm_ik
    from op2motion.kinematics.report import evaluate
    from op2motion.robot.joints import book_to_servo, servo_dict

    outputs = OutputSet({"plot": args.plot} if args.plot else {})
    angles, name, _ = angles_from(args, spec)
    delta = vec3(args.delta, "delta")
    tol = args.tol_mm / 1000.0
    res = solve_arm_ik(angles, args.hand, delta, spec, args.model, single_step=args.single_step, tol=tol,
                       enforce_limits=not args.allow_limits)
    arm = ARMS[args.hand]
    converged = res.mode == "single-step" or res.error_m <= tol
    result = {
        "hand": args.hand, "model": res.model, "mode": res.mode, "iterations": res.iterations,
        "joint_deltas_deg": {n: float(math.degrees(v)) for n, v in zip(arm.names, res.deltas)},
        **res.angles.degrees(),
        "requested_delta": [float(v) for v in res.requested],
        "achieved_delta": [float(v) for v in res.achieved],
        "error_m": res.error_m, "converged": converged,
        "servo_deg": servo_dict(book_to_servo(res.angles, spec)[0], spec),
        "limit_violations": [v.as_dict() for v in res.limit_violations],
    }
    deltas = ", ".join(f"d{n} = {math.degrees(v):+.2f}°" for n, v in zip(arm.names, res.deltas))
    text = (f"{res.mode} on the {res.model.upper()} model, {res.iterations} iteration(s): {deltas}\n"
            f"hand moved {', '.join(f'{v * 1000:+.2f}' for v in res.achieved)} mm "
            f"(asked {', '.join(f'{v * 1000:+.2f}' for v in res.requested)} mm), error {res.error_m * 1000:.3f} mm")
    failure: CheckFailed | None = None
    if res.limit_violations and not args.allow_limits:
        failure = CheckFailed(f"refused: {res.limit_violations[0].describe()}; pass --allow-limits to accept")
    elif not converged:
        failure = Unreachable(f"target not reached: best residual {res.error_m * 1000:.3f} mm (tolerance "
                              f"{args.tol_mm} mm); it lies outside what this arm can reach on the "
                              f"{res.model.upper()} model", res.error_m, tol)
    if args.plot and failure is None:
        start = evaluate(res.initial, spec, res.model)
        target = start.points.point(arm.hand)[0] + res.requested
        lines = [f"{args.hand} hand moved by ({', '.join(f'{v * 1000:+.1f}' for v in res.requested)}) mm with "
                 f"{res.mode} arm IK: {deltas}; error {res.error_m * 1000:.3f} mm"]
        drawing = Drawing((res.model,), target=target, lines=lines, ghost=res.initial)
        png, _, _ = pose_figure(f"{name} + arm IK", res.angles, spec, drawing)
        outputs.put("plot", png)
        result["png"] = str(outputs.commit()["plot"])
    emit(args, result, text)
    if failure is not None:
        raise failure
    return 0
