"""What ``motion play``, ``motion plan`` and ``motion line`` share on the command line: the physics and output
flags, the request they make (:class:`~op2motion.tasks.motion.MotionCheck`), and the delivery of a task's result
(:func:`deliver`: the files written when it is a yes, the report printed, exit 1 when it is a no)."""

from __future__ import annotations

import argparse
from contextlib import nullcontext
from typing import TYPE_CHECKING, Any, ContextManager

from op2motion.commands.common import emit, engines_of, output_path, physics_args, png_path, progress, warn
from op2motion.errors import CheckFailed

if TYPE_CHECKING:
    from op2motion.tasks.motion import MotionCheck
    from op2motion.tasks.result import TaskResult


def motion_physics_args(p: argparse.ArgumentParser) -> None:
    """--validate, --engine, --push, --plot and --csv."""
    physics_args(p, True, "with --validate: push the torso N newtons for 0.1 s halfway through (four directions)")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="q, q̇, q̈ per joint and the CoM/ZMP/CoP tracks")
    p.add_argument("--csv", type=output_path, metavar="CSV", help="the goals every 8 ms as CSV")


def motion_check(args: argparse.Namespace) -> MotionCheck:
    """The check and outputs the flags ask for (``--out`` where the command has it)."""
    from op2motion.tasks.motion import MotionCheck

    return MotionCheck(args.validate, engines_of(args), args.push, args.plot, args.csv, getattr(args, "out", None))


def physics_progress(args: argparse.Namespace) -> ContextManager[Any]:
    """Progress of the physics check on stderr when ``--validate`` asks for one (None otherwise)."""
    return progress(args, "physics", "s") if args.validate else nullcontext(None)


def deliver(args: argparse.Namespace, result: TaskResult) -> int:
    """Write a yes's files (atomically, together), print the report (``--json``: :meth:`~.TaskResult.as_dict`),
    and turn a no into exit 1 with its phrase (nothing written); a task refused before its checks prints nothing."""
    from op2motion.fileio import OutputSet

    if not result.checked:
        raise CheckFailed(str(result.problem))
    outputs = OutputSet({role: out.path for role, out in result.outputs.items()})
    for role, out in result.outputs.items():
        outputs.put(role, out.content)
    written = outputs.commit() if result.ok else {}
    files = {k: str(v) for k, v in written.items()}
    report = result.as_dict(files)
    if result.warnings is not None:
        warn(args, report, list(result.warnings))
    emit(args, report, "\n".join([*result.lines, *(f"  wrote {p}" for p in written.values())]))
    if not result.ok:
        raise CheckFailed(str(result.problem))
    return 0
