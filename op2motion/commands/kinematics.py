"""CLI commands of the kinematic models: fk, convert, plot, arm-ik."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from ..cli import angles_from, emit, vec3
from ..errors import InputError
from ..spec import Spec


def cmd_fk(args: argparse.Namespace, spec: Spec) -> int:
    from ..summary import evaluate, human

    angles, _ = angles_from(args, spec)
    sp = vec3(args.sp, "--sp") or (0.0, 0.0, 0.0)
    _, result = evaluate(angles, spec, args.model, args.br, sp, math.radians(args.gamma))
    emit(args, result, human(result))
    return 0


def cmd_convert(args: argparse.Namespace, spec: Spec) -> int:
    from ..joints import book_to_servo, servo_from_mapping, servo_to_book, servo_to_ticks

    if args.servo_deg is not None:
        if args.th is not None or args.phi is not None:
            raise InputError("give either --servo-deg or --th/--phi, not both")
        text = args.servo_deg
        if not text.lstrip().startswith("{"):
            try:
                text = Path(text).read_text(encoding="utf-8")
            except OSError as exc:
                raise InputError(f"--servo-deg: expected a JSON object or a file holding one: {exc.strerror}") from None
        try:
            mapping = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(f"--servo-deg: not valid JSON: {exc.msg}") from None
        servo = servo_from_mapping(mapping, spec)
        angles = servo_to_book(servo, args.support, spec)
    else:
        angles, _ = angles_from(args, spec)
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
    from ..plot import PoseFigure, plot_poses
    from ..summary import evaluate, human

    angles, name = angles_from(args, spec, "pose_positional")
    target = vec3(args.target, "--target")
    models = ("dh", "pb") if args.model == "both" else (args.model,)
    figures, results = [], []
    for model in models:
        points, result = evaluate(angles, spec, model, args.br)
        figures.append(PoseFigure(points, np.array(result["com"]), f"{name} ({model.upper()})", args.br, target))
        results.append(result)
    out = plot_poses(figures, spec, args.output, title=f"{spec.name}: {name}, {angles.support} support")
    summary = {"png": str(out), "models": {r["model"]: {k: r[k] for k in ("com", "stability_margin_m", "left_hand",
                                                                          "right_hand", "swing_foot_min_z")}
                                           for r in results}}
    emit(args, summary, "\n\n".join(human(r) for r in results) + f"\n\nwrote {out}")
    return 0


def cmd_arm_ik(args: argparse.Namespace, spec: Spec) -> int:
    from ..arm_ik import ARMS, solve_arm_ik
    from ..errors import CheckFailed
    from ..joints import book_to_servo, servo_dict
    from ..kinematics import forward
    from ..plot import PoseFigure, plot_poses

    angles, name = angles_from(args, spec)
    delta = vec3(args.delta, "--delta")
    if not (math.isfinite(args.tol_mm) and args.tol_mm > 0):
        raise InputError(f"--tol-mm: expected a positive number, got {args.tol_mm}")
    res = solve_arm_ik(angles, args.hand, delta, spec, args.model, args.single_step, args.tol_mm / 1000.0,
                       enforce_limits=not args.allow_limits)
    arm = ARMS[args.hand]
    converged = res.mode == "single-step" or res.error_m <= args.tol_mm / 1000.0
    result = {
        "hand": args.hand, "model": res.model, "mode": res.mode, "iterations": res.iterations,
        "joint_deltas_deg": {n: float(math.degrees(v)) for n, v in zip(arm.names, res.deltas)},
        **res.angles.degrees(),
        "requested_delta": [float(v) for v in res.requested],
        "achieved_delta": [float(v) for v in res.achieved],
        "error_m": res.error_m, "converged": converged,
        "servo_deg": servo_dict(book_to_servo(res.angles, spec)[0], spec),
        "limit_violations": res.limit_violations,
    }
    if args.plot:
        after = forward(res.angles, spec, res.model)
        before = forward(res.initial, spec, res.model)
        target = before.point(arm.hand)[0] + res.requested
        fig = PoseFigure(after, after.com[:, 0], f"{name} + arm IK ({res.model.upper()})", target=target, ghost=before)
        result["png"] = str(plot_poses([fig], spec, args.plot, title=f"{args.hand} hand moved by "
                                       f"{', '.join(f'{v * 1000:+.0f}' for v in res.requested)} mm"))
    deltas = ", ".join(f"d{n} = {math.degrees(v):+.2f}°" for n, v in zip(arm.names, res.deltas))
    text = (f"{res.mode} on the {res.model.upper()} model, {res.iterations} iteration(s): {deltas}\n"
            f"hand moved {', '.join(f'{v * 1000:+.2f}' for v in res.achieved)} mm "
            f"(asked {', '.join(f'{v * 1000:+.2f}' for v in res.requested)} mm), error {res.error_m * 1000:.3f} mm")
    emit(args, result, text)
    if res.limit_violations and not args.allow_limits:
        v = res.limit_violations[0]
        raise CheckFailed(f"refused: {v['joint']} would be at {v['deg']:.1f}° outside [{v['lower_deg']}, "
                          f"{v['upper_deg']}]°; pass --allow-limits to accept")
    if not converged:
        raise CheckFailed(f"target not reached: best residual {res.error_m * 1000:.3f} mm "
                          f"(tolerance {args.tol_mm} mm); it lies outside what this arm can reach on the "
                          f"{res.model.upper()} model")
    return 0
