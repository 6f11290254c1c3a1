"""What ``motion play``, ``motion plan`` and ``motion line`` share on the command line: the physics and output
flags, the request they make (:class:`~op2motion.tasks.motion.MotionCheck`) and the physics check's progress."""

from __future__ import annotations

import argparse
from contextlib import nullcontext
from typing import TYPE_CHECKING, Any, ContextManager

from op2motion.commands.common import engines_of, output_path, physics_args, png_path, progress

if TYPE_CHECKING:
    from op2motion.fileio import OutputSet
    from op2motion.tasks.motion import MotionCheck


def motion_physics_args(p: argparse.ArgumentParser) -> None:
    """--validate, --engine, --push, --ball, --plot and --csv."""
    physics_args(p, True, "with --validate: push the torso N newtons for 0.1 s halfway through (four directions)")
    p.add_argument("--ball", type=float, nargs=2, metavar=("X", "Y"),
                   help="with --validate: a size-1 football on the floor at X Y [m] (the start's support sole's frame: "
                        "X forward, Y left; e.g. 0.14 -0.086 in front of the right foot from walk-ready); the report "
                        "says how fast and which way the motion sent it")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="q, q̇, q̈ per joint and the CoM/ZMP/CoP tracks")
    p.add_argument("--csv", type=output_path, metavar="CSV", help="the goals every 8 ms as CSV")


def motion_check(args: argparse.Namespace) -> MotionCheck:
    """The check and outputs the flags ask for (``--out`` where the command has it)."""
    from op2motion.errors import InputError
    from op2motion.physics import Ball
    from op2motion.tasks.motion import MotionCheck

    ball = getattr(args, "ball", None)
    if ball is not None and not args.validate:
        raise InputError("expected --ball only with --validate (the ball lies in the physics check)", "ball")
    return MotionCheck(args.validate, engines_of(args), args.push, args.plot, args.csv, getattr(args, "out", None),
                       None if ball is None else Ball(*ball))


def motion_outputs(args: argparse.Namespace) -> OutputSet:
    """The output paths the flags name (``--plot``, ``--csv``, ``--out``), checked before any work."""
    from op2motion.fileio import OutputSet

    return OutputSet({k: getattr(args, k) for k in ("plot", "csv", "out") if getattr(args, k, None)})


def physics_progress(args: argparse.Namespace) -> ContextManager[Any]:
    """Progress of the physics check on stderr when ``--validate`` asks for one (None otherwise)."""
    return progress(args, "physics", "s") if args.validate else nullcontext(None)
