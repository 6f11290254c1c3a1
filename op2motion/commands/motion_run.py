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
    """--validate, --engine, --push, --plot and --csv."""
    physics_args(p, True, "with --validate: push the torso N newtons for 0.1 s halfway through (four directions)")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="q, q̇, q̈ per joint and the CoM/ZMP/CoP tracks")
    p.add_argument("--csv", type=output_path, metavar="CSV", help="the goals every 8 ms as CSV")


def motion_check(args: argparse.Namespace) -> MotionCheck:
    """The check and outputs the flags ask for (``--out`` where the command has it)."""
    from op2motion.tasks.motion import MotionCheck

    return MotionCheck(args.validate, engines_of(args), args.push, args.plot, args.csv, getattr(args, "out", None))


def motion_outputs(args: argparse.Namespace) -> OutputSet:
    """The output paths the flags name (``--plot``, ``--csv``, ``--out``), checked before any work."""
    from op2motion.fileio import OutputSet

    return OutputSet({k: getattr(args, k) for k in ("plot", "csv", "out") if getattr(args, k, None)})


def physics_progress(args: argparse.Namespace) -> ContextManager[Any]:
    """Progress of the physics check on stderr when ``--validate`` asks for one (None otherwise)."""
    return progress(args, "physics", "s") if args.validate else nullcontext(None)
