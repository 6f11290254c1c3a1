"""CLI commands of the physics layer: urdf, validate."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from op2motion.commands.common import add_command, emit, number, output_path, progress_enabled
from op2motion.model.servo import MAX_STIFFNESS_SCALE
from op2motion.physics import DEFAULT_SECONDS, ENGINES, MAX_PUSH_N, MAX_SECONDS, MIN_SECONDS

SECONDS = number(MIN_SECONDS, MAX_SECONDS, "s")


def register(sub: Any) -> None:
    """Add urdf and validate."""
    p = add_command(sub, "urdf", cmd_urdf, "the URDF generated from the spec (stdout, or -o FILE)")
    p.add_argument("-o", "--output", type=output_path, metavar="FILE", help="write the URDF here (atomically)")

    p = add_command(sub, "validate", cmd_validate, "physics check: does a pose stand? (exit 0 yes, 1 no)",
                    "Place the pose on the floor where its servos hold it against gravity (sagged; else ramp gravity "
                    "in), hold it with the calibrated MX-28 servo model at "
                    "1 kHz and judge it: stable, or the reasons it is not (tilt, com_drop, ground_contact, "
                    "swing_foot_contact, self_collision, torque_saturation, joint_limit, slip).")
    p.add_argument("pose", metavar="POSE", help="pose file (schema op2motion.pose/1)")
    p.add_argument("--engine", choices=(*ENGINES, "both"), default="pybullet",
                   help="physics engine (default pybullet); both: run both and say where they disagree")
    p.add_argument("--seconds", type=SECONDS, default=DEFAULT_SECONDS,
                   help=f"simulated time [s] (default {DEFAULT_SECONDS:g})")
    p.add_argument("--push", type=number(0.0, MAX_PUSH_N, "N"), default=0.0, metavar="N",
                   help="also push the torso with N newtons for 0.1 s in four directions (separate runs)")
    p.add_argument("--stiffness", type=number(0.0, MAX_STIFFNESS_SCALE, open_low=True), default=1.0,
                   help="scale the servos' stiffness (default 1: the MX-28 at P = 32)")
    p.add_argument("--voltage", type=float, choices=(11.1, 12.0, 14.8), default=None,
                   help="servo supply voltage [V], one of the MX-28's ratings (default: the spec's, 12 V)")
    p.add_argument("--gui-png", type=output_path, metavar="PNG", help="snapshot of the final state (TinyRenderer)")


def cmd_urdf(args: argparse.Namespace, spec: Any) -> int:
    """``op2motion urdf``."""
    from op2motion.fileio import OutputSet
    from op2motion.model.urdf import build_urdf, total_mass

    text = build_urdf(spec)
    facts = {"joints": len(spec.joints), "mass_kg": round(total_mass(spec), 6)}
    if args.output:
        outputs = OutputSet({"output": args.output})
        outputs.put("output", text)
        out = outputs.commit()["output"]
        emit(args, {"path": str(out), **facts}, f"wrote {out}: {len(spec.joints)} joints, {total_mass(spec):.3f} kg")
    elif args.json:
        emit(args, {"urdf": text, **facts}, "")
    else:
        sys.stdout.write(text)
    return 0


def cmd_validate(args: argparse.Namespace, spec: Any) -> int:
    """``op2motion validate``: one engine, or both compared."""
    from tqdm import tqdm

    from op2motion.errors import CheckFailed
    from op2motion.fileio import OutputSet
    from op2motion.formats.posefile import read_pose
    from op2motion.model.dynamics import dynamics_for
    from op2motion.physics import steps_for, validate

    outputs = OutputSet({"gui_png": args.gui_png} if args.gui_png else {})
    pose = read_pose(args.pose, spec)
    engines = ENGINES if args.engine == "both" else (args.engine,)
    runs = len(engines) * (1 + (4 if args.push else 0))
    verdicts = {}
    with tqdm(total=steps_for(args.seconds) * runs, desc="physics", unit="step", leave=False,
              disable=not progress_enabled(args)) as bar:
        for engine in engines:
            verdicts[engine] = validate(pose.servo, pose.support, spec, args.seconds, engine, args.push,
                                        args.stiffness, snapshot=bool(args.gui_png) and engine == engines[0],
                                        on_step=bar.update, voltage=args.voltage)
    static = dynamics_for(spec).static_torques(pose.servo, pose.support)
    first = verdicts[engines[0]]
    agree = len({v.stable for v in verdicts.values()}) == 1
    result: dict[str, Any] = {**first.as_dict(), "pose": pose.name, "support": pose.support,
                              "static_torque_nm": {n: float(x) for n, x in zip(spec.joint_names, static.torques)},
                              "static_worst_joint": static.worst_joint,
                              "static_worst_ratio": round(static.worst_ratio, 4)}
    if len(engines) > 1:
        result = {"pose": pose.name, "support": pose.support, "engine": "both", "agree": agree,
                  "stable": agree and first.stable, "engines": {e: v.as_dict() for e, v in verdicts.items()}}
    if args.gui_png and first.snapshot_png is not None:
        outputs.put("gui_png", first.snapshot_png)
        result["png"] = str(outputs.commit()["gui_png"])
    lines = [f"{pose.name} ({pose.support} support): {v.summary()}" for v in verdicts.values()]
    lines.append(f"  static model (pinocchio): {abs(static.worst_torque_nm):.2f} N·m at {static.worst_joint}")
    if len(engines) > 1:
        lines.append("  the engines agree" if agree else "  THE ENGINES DISAGREE")
    emit(args, result, "\n".join(lines))
    if not agree:
        raise CheckFailed(f"{pose.name}: the engines disagree (" + ", ".join(
            f"{e}: {'stands' if v.stable else v.reason}" for e, v in verdicts.items()) + ")")
    if not first.stable:
        raise CheckFailed(f"{pose.name} does not stand: {first.reason}")
    pushed = [p for v in verdicts.values() for p in v.pushes if not p.stable]
    if pushed:
        raise CheckFailed(f"{pose.name} stands but falls when pushed {pushed[0].force_n:g} N {pushed[0].direction} "
                          f"({', '.join(pushed[0].reasons)})")
    return 0
