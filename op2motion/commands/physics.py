"""CLI commands of the physics layer: urdf, validate."""

from __future__ import annotations

import argparse
from typing import Any

from op2motion.commands.common import (
    add_command,
    engines_of,
    number,
    output_path,
    physics_args,
    png_path,
    progress,
)
from op2motion.commands.deliver import deliver
from op2motion.model.servo import MAX_STIFFNESS_SCALE
from op2motion.physics import DEFAULT_SECONDS, MAX_SECONDS, MIN_SECONDS
from op2motion.robot.spec import Spec

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
    physics_args(p, False, "also push the torso with N newtons for 0.1 s in four directions (separate runs)")
    p.add_argument("--seconds", type=SECONDS, default=DEFAULT_SECONDS,
                   help=f"simulated time [s] (default {DEFAULT_SECONDS:g})")
    p.add_argument("--stiffness", type=number(0.0, MAX_STIFFNESS_SCALE, open_low=True), default=1.0,
                   help="scale the servos' stiffness (default 1: the MX-28 at P = 32)")
    p.add_argument("--voltage", type=float, choices=(11.1, 12.0, 14.8), default=None,
                   help="servo supply voltage [V], one of the MX-28's ratings (default: the spec's, 12 V)")
    p.add_argument("--gui-png", type=png_path, metavar="PNG", help="snapshot of the final state (TinyRenderer)")
    p.add_argument("--robust", action="store_true",
                   help="hold the pose on every member of the robustness family (torso CoM and mass from the spec's "
                        "uncertainty, servo stiffness x0.6-1.6, friction 0.5-1.0, 16 ms IMU latency) and print the "
                        "table; exit 1 unless every run stands")


def cmd_urdf(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion urdf``."""
    from op2motion.fileio import OutputSet
    from op2motion.tasks.files import urdf

    outputs = OutputSet({"output": args.output} if args.output else {})
    return deliver(args, urdf(spec, outputs.paths.get("output"), args.json), outputs, "none")


def cmd_validate(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion validate``: one engine, or both compared, or the robustness family."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.posefile import read_pose
    from op2motion.tasks.validate import Validation, validate_pose, validate_pose_robust

    outputs = OutputSet({"gui_png": args.gui_png} if args.gui_png else {})
    pose = read_pose(args.pose, spec)
    how = Validation(args.seconds, engines_of(args), args.push, args.stiffness, args.voltage, args.gui_png)
    if args.robust:
        with progress(args, "robust", "run") as on_progress:
            family = validate_pose_robust(pose, spec, how, on_progress)
        return deliver(args, family, outputs, "none")
    with progress(args, "physics", "s") as on_progress:
        result = validate_pose(pose, spec, how, on_progress)
    return deliver(args, result, outputs, "none")
