"""The ``op2motion`` command line: thin subcommands, each calling one library function.

Every subcommand takes ``--json`` (the result as JSON on stdout, nothing else there). Errors are one line on
stderr; exit code 2 for bad input, 1 for a check that ran and failed, 0 for success. Angles on the command line
are degrees, lengths metres.
"""

from __future__ import annotations

import argparse
import json
import math
import os
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


def cmd_optimize(args: argparse.Namespace, spec: Spec) -> int:
    from tqdm import tqdm

    from .errors import CheckFailed
    from .export.library import pose_to_json, write_pose
    from .plot import PoseFigure, plot_cost_curve, plot_poses
    from .posture.cost import PostureProblem
    from .posture.pso import PSOSettings
    from .posture.solve import optimize_posture

    target = _vec3(args.target, "--target")
    problem = PostureProblem(args.support, args.hand, target, args.br, args.model).validated()
    settings = PSOSettings(args.particles, args.iters, seed=args.seed).validated()
    name = args.name or problem.name
    out = Path(args.out) if args.out else Path("poses") / f"{name}.json"
    png = Path(args.plot) if args.plot else out.with_suffix(".png")
    cost_png = out.with_name(out.stem + "_cost.png")
    interactive = sys.stderr.isatty() and not args.json
    validations: dict[int, Any] = {}

    def physics_check(res: Any) -> tuple[bool, str]:
        from .physics import validate_servo

        v = validate_servo(res.pose(name, spec).servo, args.support, spec, args.seconds)
        validations[res.settings.seed] = v
        return v.stable, f"does not stand in physics ({v.reason})"

    with tqdm(total=settings.iterations * (1 + args.restarts), desc="PSO", unit="it", disable=not interactive,
              leave=False) as bar:
        res = optimize_posture(problem, spec, settings, not args.no_refine,
                               on_iteration=lambda best: (bar.update(), bar.set_postfix(cost=f"{best:.4f}")),
                               restarts=args.restarts, check=physics_check if args.validate else None)
    command = "op2motion optimize " + " ".join(sys.argv[2:]) if len(sys.argv) > 1 else "op2motion optimize"
    pose = res.pose(name, spec, {"command": command})
    m = res.metrics
    result: dict[str, Any] = {
        "pose": json.loads(pose_to_json(pose, spec)), "reached": res.reached, "message": res.message,
        "cost": m["cost"], "hand_error_m": m["hand_error_m"], "com": m["com"],
        "stability_margin_m": m["stability_margin_m"], "com_full": m["com_full"],
        "stability_margin_full_m": m["stability_margin_full_m"], "swing_foot_min_z": m["swing_foot_min_z"],
        "iterations": int(len(res.pso.history)), "attempts": m["attempts"], "refinement": res.method,
        "seconds": round(res.seconds, 3),
    }
    lines = [f"{args.hand} hand to ({', '.join(f'{v:.3f}' for v in target)}) m on the {args.support} foot, "
             f"br {args.br}: {res.message}",
             f"  CoM ({m['com'][0]:+.3f}, {m['com'][1]:+.3f}, {m['com'][2]:.3f}) m [lumped], stability margin "
             f"{m['stability_margin_m'] * 1000:.1f} mm (full-inertia CoM: {m['stability_margin_full_m'] * 1000:.1f} mm)"
             f", swing foot {m['swing_foot_min_z'] * 1000:.1f} mm above the floor, torso tilt {m['torso_tilt_deg']:.0f}°",
             f"  PSO {settings.particles} particles x {settings.iterations} iterations (seed {res.settings.seed}, "
             f"attempt {m['attempts']}), refinement: {res.method}, {res.seconds:.2f} s"]
    if res.settings.seed in validations:
        v = validations[res.settings.seed]
        result["validation"] = v.as_dict()
        lines.append(f"  physics ({args.seconds:g} s): {'STABLE' if v.stable else 'NOT STABLE'} ({v.reason}), "
                     f"tilt {v.max_tilt_deg:.1f}°, torque {v.max_torque_nm:.2f} N·m at {v.worst_joint}")
    if not res.reached:
        _emit(args, result, "\n".join(lines))
        raise CheckFailed(f"{res.message}; nothing written")
    write_pose(pose, out, spec)
    fig = PoseFigure(forward_points(res, spec), np.array(m["com"]), name, args.br, target)
    plot_poses([fig], spec, png, title=f"{name}: {res.message}")
    plot_cost_curve(res.pso.history, cost_png, f"PSO cost, {name}")
    result["files"] = {"pose": str(out), "png": str(png), "cost_png": str(cost_png)}
    lines.append(f"  wrote {out}, {png}, {cost_png}")
    _emit(args, result, "\n".join(lines))
    return 0


def forward_points(res: Any, spec: Spec) -> Any:
    """D-H body points of a posture result (for its figure)."""
    from .kinematics import forward

    return forward(res.angles, spec, "dh")


def cmd_export(args: argparse.Namespace, spec: Spec) -> int:
    from .export.action import read_action, write_poses
    from .export.library import read_pose
    from .export.tables import write_table

    poses = [read_pose(p, spec) for p in args.poses]
    if args.format == "action":
        base = read_action(args.base, spec) if args.base else None
        out = write_poses(poses, spec, args.output, args.page, args.time, base)
        text = (f"wrote {out}: {len(poses)} pose(s) in pages {args.page}..{args.page + len(poses) - 1}"
                if poses else f"wrote {out}: the base, unchanged")
    else:
        if not poses:
            raise InputError(f"export --format {args.format}: expected at least one pose file")
        out = write_table(args.format, poses, spec, args.output, args.time)
        text = f"wrote {out}: {len(poses)} pose(s)"
    _emit(args, {"path": str(out), "format": args.format, "poses": [p.name for p in poses]}, text)
    return 0


def cmd_import_action(args: argparse.Namespace, spec: Spec) -> int:
    from .export.action import list_pages, page_to_pose, read_action, requested_page
    from .export.library import pose_to_json, write_pose

    data = read_action(args.file, spec)
    if args.page is not None:
        pose = page_to_pose(requested_page(data, args.page, spec, args.file), spec, args.name)
        if args.out:
            write_pose(pose, args.out, spec)
        doc = json.loads(pose_to_json(pose, spec))
        _emit(args, {"page": args.page, "pose": doc, "path": args.out},
              f"page {args.page} -> pose {pose.name!r}" + (f", wrote {args.out}" if args.out else ""))
        return 0
    if args.out:
        raise InputError("--out needs --page N")
    pages = list_pages(data, spec, args.file)
    result = {"pages": [{"index": p.index, "name": p.name, "repeat": p.repeat, "next": p.next,
                         "steps": [{"ticks": {str(k): v for k, v in s.ticks.items()}, "pause": s.pause, "time": s.time}
                                   for s in p.steps]} for p in pages]}
    text = "\n".join(f"{p.index:3d} {p.name:<14} {len(p.steps)} step(s)" + (f" -> page {p.next}" if p.next else "")
                     for p in pages)
    _emit(args, result, text)
    return 0


def cmd_library_build(args: argparse.Namespace, spec: Spec) -> int:
    from tqdm import tqdm

    from .posture.library_build import axis, build_library, grid_jobs
    from .posture.pso import PSOSettings

    jobs = grid_jobs(args.hands, args.supports, args.br, axis(*args.x, "--x"), axis(*args.y, "--y"),
                     axis(*args.z, "--z"))
    settings = PSOSettings(args.particles, args.iters, seed=args.seed).validated()
    if args.workers < 0:
        raise InputError(f"--workers: expected 0 (all cores) or more, got {args.workers}")
    with tqdm(total=len(jobs), desc="library", unit="pose", disable=not sys.stderr.isatty() or args.json) as bar:
        summary = build_library(jobs, spec, args.out, settings, args.workers, args.validate, args.spec,
                                on_done=lambda row: bar.update())
    text = (f"{summary['targets']} targets: {summary['solved']} reached, {summary['failed']} not, "
            f"{summary['skipped']} already done; {summary['seconds']:.1f} s; index {summary['index']}")
    _emit(args, summary, text)
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
             f"one PyBullet validation (3 s simulated): {result['validate_ms']:.0f} ms",
             f"one PSO posture solve (50 particles x 200 iterations, D-H): {result['pso_solve_ms']:.0f} ms "
             "(target <= 150 ms)"]
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

    p = add("optimize", cmd_optimize, "PSO posture: reach a target with one hand while the CoM stays over the foot")
    p.add_argument("--support", choices=("left", "right"), default="left", help="support foot (default left)")
    p.add_argument("--hand", choices=("left", "right"), default="left", help="reaching hand (default left)")
    p.add_argument("--target", type=float, nargs=3, default=(0.10, 0.05, 0.07), metavar=("X", "Y", "Z"),
                   help="target in the support-foot frame [m] (default 0.10 0.05 0.07)")
    p.add_argument("--br", type=float, default=0.7, help="boundary ratio of the support rectangle (default 0.7)")
    p.add_argument("--model", choices=("dh", "pb"), default="dh", help="kinematic model of the PSO (default dh)")
    p.add_argument("--particles", type=int, default=50, help="swarm size (default 50)")
    p.add_argument("--iters", type=int, default=200, help="PSO iterations (default 200)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--restarts", type=int, default=2, help="extra solves with the next seeds if one fails (default 2)")
    p.add_argument("--no-refine", action="store_true", help="skip the local refinement (hand within 5 mm)")
    p.add_argument("--name", help="pose name (default from hand, support, target, br)")
    p.add_argument("--out", metavar="FILE", help="pose file (default poses/NAME.json)")
    p.add_argument("--plot", metavar="PNG", help="pose figure (default beside the pose file)")
    p.add_argument("--validate", action="store_true", help="check the pose in PyBullet before writing it")
    p.add_argument("--seconds", type=float, default=3.0, help="simulated time of --validate [s]")

    p = add("export", cmd_export, "pose files -> ROBOTIS action file, Webots motion or CSV")
    p.add_argument("poses", nargs="*", metavar="POSE", help="pose files, in order")
    p.add_argument("--format", choices=("action", "webots", "csv"), required=True, help="output format")
    p.add_argument("--base", metavar="FILE", help="action file to start from (default: reset pages)")
    p.add_argument("--page", type=int, default=1, help="first page to write (action format, default 1)")
    p.add_argument("--time", type=float, default=1.0, help="seconds per pose (default 1.0)")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="file to write (atomically)")

    p = add("import-action", cmd_import_action, "list the pages of a ROBOTIS action file, or turn one into a pose")
    p.add_argument("file", metavar="FILE", help="motion_4096.bin")
    p.add_argument("--page", type=int, help="page to turn into a pose (its last step)")
    p.add_argument("--out", metavar="POSE", help="write that pose file (with --page)")
    p.add_argument("--name", help="pose name (default: the page name)")

    lib = sub.add_parser("library", help="the pose library", description="the pose library")
    lib_sub = lib.add_subparsers(dest="library_command", required=True, parser_class=_Parser)
    p = lib_sub.add_parser("build", help="optimise a grid of reach targets in parallel (resumable)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=cmd_library_build)
    p.add_argument("--hands", nargs="+", choices=("left", "right"), default=["left", "right"])
    p.add_argument("--supports", nargs="+", choices=("left", "right"), default=["left", "right"])
    p.add_argument("--br", type=float, nargs="+", default=[0.7], help="boundary ratios (default 0.7)")
    p.add_argument("--x", type=float, nargs=3, default=(0.06, 0.14, 3), metavar=("START", "STOP", "N"),
                   help="target x values [m] (default 0.06 0.14 3)")
    p.add_argument("--y", type=float, nargs=3, default=(-0.06, 0.06, 3), metavar=("START", "STOP", "N"),
                   help="target y values [m] (default -0.06 0.06 3)")
    p.add_argument("--z", type=float, nargs=3, default=(0.05, 0.15, 3), metavar=("START", "STOP", "N"),
                   help="target z values [m] (default 0.05 0.15 3)")
    p.add_argument("--out", default="poses/library", help="library folder (default poses/library)")
    p.add_argument("--workers", type=int, default=0, help="worker processes (default: one per core)")
    p.add_argument("--particles", type=int, default=50)
    p.add_argument("--iters", type=int, default=200)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--validate", action="store_true", help="check every reached pose in PyBullet (2 s)")

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
    except Exception as exc:  # a bug, not bad input: still one line (OP2MOTION_DEBUG=1 shows the traceback)
        if os.environ.get("OP2MOTION_DEBUG"):
            raise
        print(f"op2motion: internal error: {type(exc).__name__}: {exc} (set OP2MOTION_DEBUG=1 for details)",
              file=sys.stderr)
        return 1
