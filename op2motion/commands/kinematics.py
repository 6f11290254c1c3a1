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
    number,
    png_path,
    vec3,
)
from op2motion.commands.deliver import deliver
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
    from op2motion.tasks.kinematics import fk

    given = angles_from(args, spec)
    angles, pose = given.angles, given.pose
    sp = vec3(args.sp, "sp") or (0.0, 0.0, 0.0)
    double = pose is not None and Support.of(pose.support).is_double
    return deliver(args, fk(angles, spec, args.model, args.br, sp, math.radians(args.gamma), double))


def _servo_mapping(text: str) -> dict[str, Any]:
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
    mapping: dict[str, Any] = doc
    return mapping


def cmd_convert(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion convert``."""
    from op2motion.robot.joints import book_to_servo, servo_from_mapping, servo_to_book
    from op2motion.tasks.kinematics import convert

    if args.servo_deg is not None:
        if args.th is not None or args.phi is not None or args.pose:
            raise InputError("give either --servo-deg, --pose or --th/--phi, not several")
        servo = servo_from_mapping(_servo_mapping(args.servo_deg), spec)
        angles = servo_to_book(servo, args.support, spec)
    else:
        angles = angles_from(args, spec).angles
        servo = book_to_servo(angles, spec)[0]
    return deliver(args, convert(angles, servo, spec))


def cmd_plot(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion plot``: the figure, with the physics verdict when asked (or recorded in the pose file)."""
    from op2motion.fileio import OutputSet
    from op2motion.tasks.kinematics import PlotRequest, plot

    outputs = OutputSet({"output": args.output})
    given = angles_from(args, spec, args.pose_positional, default_standing=True)
    angles, name, pose = given.angles, given.name, given.pose
    target = vec3(args.target, "target")
    models = MODELS if args.model == "both" else (args.model,)
    request = PlotRequest(name, angles, outputs.paths["output"], pose, models, args.br, target,
                          args.seconds if args.validate else None)
    return deliver(args, plot(request, spec), outputs, "none")


def cmd_arm_ik(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion arm-ik``."""
    from op2motion.fileio import OutputSet
    from op2motion.tasks.kinematics import ArmMove, arm_ik

    outputs = OutputSet({"plot": args.plot} if args.plot else {})
    given = angles_from(args, spec)
    angles, name = given.angles, given.name
    delta = vec3(args.delta, "delta")
    if delta is None:                        # a required flag: argparse has it
        raise InputError("expected --delta DX DY DZ", "delta")
    request = ArmMove(name, angles, args.hand, delta, args.model, args.single_step, args.tol_mm, args.allow_limits,
                      args.plot)
    return deliver(args, arm_ik(request, spec), outputs, "none")
