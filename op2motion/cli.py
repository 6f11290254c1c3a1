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
from typing import Any, Callable, Sequence


from . import __version__
from .errors import InputError, Op2MotionError
from .spec import Spec, load_spec


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one-line :class:`InputError` instead of exiting."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InputError(f"{self.prog}: {message}")


def emit(args: argparse.Namespace, result: dict[str, Any], text: str) -> None:
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


def angles_from(args: argparse.Namespace, spec: Spec, pose_attr: str = "pose"):
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


def vec3(values: Sequence[float] | None, name: str) -> tuple[float, float, float] | None:
    if values is None:
        return None
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise InputError(f"{name}: expected 3 finite numbers, got {list(values)}")
    return (float(values[0]), float(values[1]), float(values[2]))


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    from .commands.bench import cmd_bench
    from .commands.files import cmd_export, cmd_import_action
    from .commands.kinematics import cmd_arm_ik, cmd_convert, cmd_fk, cmd_plot
    from .commands.physics import cmd_urdf, cmd_validate
    from .commands.posture import cmd_library_build, cmd_optimize

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
