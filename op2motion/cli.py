"""The ``op2motion`` command line: thin subcommands, each calling one library function.

Every subcommand takes ``--json`` (the result as JSON on stdout, nothing else there). Errors are one line on
stderr; exit code 2 for bad input, 1 for a check that ran and failed, 0 for success. Angles on the command line
are degrees, lengths metres.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from . import __version__
from .errors import InputError, Op2MotionError
from .spec import Spec, load_spec


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one-line :class:`InputError` instead of exiting."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InputError(f"{self.prog}: {message}")


def _emit(args: argparse.Namespace, result: dict[str, Any], text: str) -> None:
    if args.json:
        json.dump(result, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    elif text:
        print(text)


def _book_args(p: argparse.ArgumentParser, required: bool = False) -> None:
    p.add_argument("--support", choices=("left", "right"), default="left", help="support foot (default left)")
    p.add_argument("--th", type=float, nargs="+", metavar="DEG", help="11 sagittal angles th1..th11 [deg]")
    p.add_argument("--phi", type=float, nargs="+", metavar="DEG", help="6 coronal angles phi1..phi6 [deg]")
    p.add_argument("--psi", type=float, nargs="+", metavar="DEG", help="3 transverse angles psi1..psi3 [deg] (default 0)")


def _angles_from(args: argparse.Namespace, spec: Spec, pose_attr: str = "pose"):
    """Book angles from --pose FILE, or --th/--phi[/--psi] --support, or the standing pose."""
    from .export.library import read_pose
    from .joints import BookAngles

    pose_path = getattr(args, pose_attr, None)
    if pose_path:
        if args.th is not None or args.phi is not None:
            raise InputError("give either a pose file or --th/--phi, not both")
        pose = read_pose(pose_path, spec)
        return pose.book(spec), pose.name
    if args.th is None and args.phi is None:
        if getattr(args, "standing", False) or pose_attr == "pose_positional":
            return BookAngles.standing(args.support), "standing"
        raise InputError("expected --th (11 angles) and --phi (6 angles) in degrees, or --pose FILE")
    if args.th is None or args.phi is None:
        raise InputError("expected both --th (11 angles) and --phi (6 angles)")
    return BookAngles.from_deg(args.th, args.phi, args.psi, args.support), "pose"


def _vec3(values: Sequence[float] | None, name: str) -> tuple[float, float, float] | None:
    if values is None:
        return None
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise InputError(f"{name}: expected 3 finite numbers, got {list(values)}")
    return (float(values[0]), float(values[1]), float(values[2]))


def cmd_fk(args: argparse.Namespace, spec: Spec) -> int:
    from .summary import evaluate, human

    angles, _ = _angles_from(args, spec)
    sp = _vec3(args.sp, "--sp") or (0.0, 0.0, 0.0)
    _, result = evaluate(angles, spec, args.model, args.br, sp, math.radians(args.gamma))
    _emit(args, result, human(result))
    return 0


def cmd_convert(args: argparse.Namespace, spec: Spec) -> int:
    from .joints import book_to_servo, servo_from_mapping, servo_to_book, servo_to_ticks

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
        angles, _ = _angles_from(args, spec)
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
    _emit(args, result, "\n".join(lines))
    return 0


def cmd_plot(args: argparse.Namespace, spec: Spec) -> int:
    from .plot import PoseFigure, plot_poses
    from .summary import evaluate, human

    angles, name = _angles_from(args, spec, "pose_positional")
    target = _vec3(args.target, "--target")
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
    _emit(args, summary, "\n\n".join(human(r) for r in results) + f"\n\nwrote {out}")
    return 0


def cmd_arm_ik(args: argparse.Namespace, spec: Spec) -> int:
    from .arm_ik import ARMS, solve_arm_ik
    from .errors import CheckFailed
    from .joints import book_to_servo, servo_dict
    from .kinematics import forward
    from .plot import PoseFigure, plot_poses

    angles, name = _angles_from(args, spec)
    delta = _vec3(args.delta, "--delta")
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
    _emit(args, result, text)
    if res.limit_violations and not args.allow_limits:
        v = res.limit_violations[0]
        raise CheckFailed(f"refused: {v['joint']} would be at {v['deg']:.1f}° outside [{v['lower_deg']}, "
                          f"{v['upper_deg']}]°; pass --allow-limits to accept")
    if not converged:
        raise CheckFailed(f"target not reached: best residual {res.error_m * 1000:.3f} mm "
                          f"(tolerance {args.tol_mm} mm); it lies outside what this arm can reach on the "
                          f"{res.model.upper()} model")
    return 0


def cmd_urdf(args: argparse.Namespace, spec: Spec) -> int:
    from .fileio import write_atomic
    from .model.urdf import build_urdf, total_mass

    text = build_urdf(spec)
    if args.output:
        write_atomic(args.output, text)
        result = {"path": args.output, "joints": len(spec.joints), "mass_kg": round(total_mass(spec), 6)}
        _emit(args, result, f"wrote {args.output}: {len(spec.joints)} joints, {total_mass(spec):.3f} kg")
    elif args.json:
        _emit(args, {"urdf": text, "joints": len(spec.joints), "mass_kg": round(total_mass(spec), 6)}, "")
    else:
        sys.stdout.write(text)
    return 0


def cmd_validate(args: argparse.Namespace, spec: Spec) -> int:
    from tqdm import tqdm

    from .errors import CheckFailed
    from .export.library import read_pose
    from .model.dynamics import COM_MODEL_FULL, dynamics_for
    from .physics import steps_for, validate_servo
    from .kinematics import forward

    pose = read_pose(args.pose, spec)
    with tqdm(total=steps_for(args.seconds), desc="physics", unit="step", disable=not sys.stderr.isatty(),
              leave=False) as bar:
        v = validate_servo(pose.servo, pose.support, spec, args.seconds, args.gui_png, on_step=bar.update)
    dyn = dynamics_for(spec)
    static = dyn.static_torques(pose.servo, pose.support)
    root = "right" if pose.support == "right" else "left"
    lumped = forward(pose.book(spec), spec).com[:, 0]
    result = {**v.as_dict(), "pose": pose.name, "support": pose.support,
              "static_torque_nm": {n: float(x) for n, x in zip(spec.joint_names, static.torques)},
              "static_worst_joint": static.worst_joint, "static_worst_ratio": round(static.worst_ratio, 4),
              "com_full": [float(x) for x in dyn.com(pose.servo, root)], "com_full_model": COM_MODEL_FULL,
              "com_lumped": [float(x) for x in lumped]}
    if args.gui_png:
        result["png"] = args.gui_png
    text = (f"{pose.name} ({pose.support} support), {args.seconds:g} s of PyBullet: "
            f"{'STABLE' if v.stable else 'NOT STABLE'} ({v.reason})\n"
            f"  torso tilt max {v.max_tilt_deg:.2f}°, CoM drift {v.com_drift_m * 1000:.1f} mm, "
            f"feet slip {v.feet_slip_m * 1000:.1f} mm\n"
            f"  servo torque (steady) max {v.max_torque_nm:.2f} N·m at {v.worst_joint} "
            f"({'ok' if v.torque_ok else 'SATURATED'}; stall {spec.servo.stall_torque_nm} N·m); static model: "
            f"{abs(static.worst_torque_nm):.2f} N·m at {static.worst_joint}\n"
            f"  self-collisions: {', '.join('-'.join(p) for p in v.self_collisions) or 'none'}")
    _emit(args, result, text)
    if not v.stable:
        raise CheckFailed(f"{pose.name} does not stand: {v.reason}")
    return 0


def cmd_bench(args: argparse.Namespace, spec: Spec) -> int:
    from .bench import run_bench

    if args.poses < 1 or args.repeat < 1:
        raise InputError("--poses and --repeat: expected positive integers")
    result = run_bench(spec, args.poses, args.repeat)
    lines = [f"{result['poses']} poses, best of {result['repeat']}, scaled to 40 000 full-body evaluations:",
             f"  projection model  {result['fk_pb_40k_ms']:8.2f} ms   (book MATLAB: 780 ms)",
             f"  D-H model         {result['fk_dh_40k_ms']:8.2f} ms   (book MATLAB: 3350 ms)",
             f"  pinocchio loop    {result['pinocchio_com_40k_ms']:8.2f} ms   (centerOfMass per configuration)",
             f"one PyBullet validation (3 s simulated): {result['validate_ms']:.0f} ms"]
    _emit(args, result, "\n".join(lines))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = _Parser(prog="op2motion", description="Whole-body motion for the ROBOTIS OP2, checked in physics.")
    parser.add_argument("--version", action="version", version=f"op2motion {__version__}")
    parser.add_argument("--spec", metavar="FILE", help="robot spec TOML (default: the shipped specs/op2.toml)")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def add(name: str, func: Callable[[argparse.Namespace, Spec], int], help_: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_, description=help_)
        p.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
        p.set_defaults(func=func)
        return p

    p = add("fk", cmd_fk, "full-body forward kinematics of one pose")
    p.add_argument("--model", choices=("dh", "pb"), default="dh", help="D-H (default) or projection model")
    _book_args(p)
    p.add_argument("--pose", metavar="FILE", help="a pose file instead of --th/--phi")
    p.add_argument("--br", type=float, default=1.0, help="boundary ratio of the support rectangle (default 1.0)")
    p.add_argument("--sp", type=float, nargs=3, metavar=("X", "Y", "Z"), help="support sole centre [m] (default 0)")
    p.add_argument("--gamma", type=float, default=0.0, metavar="DEG", help="heading of the support foot [deg]")

    p = add("convert", cmd_convert, "book variables <-> servo angles <-> Dynamixel ticks")
    _book_args(p)
    p.add_argument("--pose", metavar="FILE", help="a pose file instead of --th/--phi")
    p.add_argument("--servo-deg", metavar="JSON", help="servo angles {joint: deg} as JSON text or a JSON file")

    p = add("plot", cmd_plot, "stick figure of a pose (front, side, top, 3D) as a PNG")
    p.add_argument("pose_positional", nargs="?", metavar="POSE", help="pose file (default: the standing pose)")
    _book_args(p)
    p.add_argument("--model", choices=("dh", "pb", "both"), default="dh", help="kinematic model(s) to draw")
    p.add_argument("--br", type=float, default=1.0, help="boundary ratio of the drawn support rectangle")
    p.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "Z"), help="mark a target [m]")
    p.add_argument("-o", "--output", required=True, metavar="PNG", help="where to write the PNG")

    p = add("arm-ik", cmd_arm_ik, "move one hand by a displacement with the Taylor-linearised arm IK")
    p.add_argument("--hand", choices=("left", "right"), required=True, help="which hand to move")
    p.add_argument("--delta", type=float, nargs=3, required=True, metavar=("DX", "DY", "DZ"),
                   help="hand displacement in the world frame [m]")
    _book_args(p)
    p.add_argument("--pose", metavar="FILE", help="a pose file instead of --th/--phi")
    p.add_argument("--single-step", action="store_true", help="the book's single Taylor step (code 2.15/2.17)")
    p.add_argument("--model", choices=("pb", "dh"), default="pb",
                   help="model to iterate on: pb (book, default) or dh (true geometry, for the real robot)")
    p.add_argument("--tol-mm", type=float, default=0.1, help="iterated mode: target tolerance [mm] (default 0.1)")
    p.add_argument("--allow-limits", action="store_true", help="accept a result outside the servo limits")
    p.add_argument("--plot", metavar="PNG", help="draw the initial and the changed pose")

    p = add("urdf", cmd_urdf, "the URDF generated from the spec (stdout, or -o FILE)")
    p.add_argument("-o", "--output", metavar="FILE", help="write the URDF here (atomically)")

    p = add("validate", cmd_validate, "PyBullet check: does a pose stand?")
    p.add_argument("pose", metavar="POSE", help="pose file (schema op2motion.pose/1)")
    p.add_argument("--seconds", type=float, default=3.0, help="simulated time [s] (default 3)")
    p.add_argument("--gui-png", metavar="PNG", help="snapshot of the final state (TinyRenderer)")

    p = add("bench", cmd_bench, "speed figures of the batched kinematic models")
    p.add_argument("--poses", type=int, default=40_000, help="batch size (figures are scaled to 40 000)")
    p.add_argument("--repeat", type=int, default=9, help="runs per figure; the best is reported")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    try:
        args = build_parser().parse_args(argv)
        spec = load_spec(args.spec)
        return int(args.func(args, spec))
    except Op2MotionError as exc:
        print(f"op2motion: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("op2motion: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
