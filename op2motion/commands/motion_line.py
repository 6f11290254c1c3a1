"""CLI: ``motion line`` (a hand along a straight line, the whole body keeping its balance)."""

from __future__ import annotations

import argparse
from typing import Any

from op2motion.commands.common import add_command, number, output_path
from op2motion.commands.deliver import deliver
from op2motion.commands.motion_run import motion_check, motion_outputs, motion_physics_args, physics_progress
from op2motion.errors import InputError
from op2motion.robot.spec import Spec

METRES = number(-1.0, 1.0, "m")
LINE_SECONDS = number(0.1, 60.0, "s")


def register_line(inner: Any) -> None:
    """Add ``motion line`` to the ``motion`` commands."""
    p = add_command(inner, "line", cmd_line, "move a hand along a straight line, the whole body keeping its balance")
    p.add_argument("pose", metavar="POSE", help="pose file to start from")
    p.add_argument("--hand", choices=("left", "right"), required=True, help="the hand that moves")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--to", type=METRES, nargs=3, metavar=("X", "Y", "Z"),
                       help="end point [m] in the support foot's frame (both feet: the left sole's)")
    where.add_argument("--by", type=METRES, nargs=3, metavar=("DX", "DY", "DZ"), help="displacement [m]")
    p.add_argument("--orientation", nargs="+", default=["free"], metavar="free|keep|DX DY DZ",
                   help="the forearm's direction: free (default), keep it, or turn it to DX DY DZ (slerp)")
    p.add_argument("--duration", type=LINE_SECONDS, required=True, metavar="S", help="seconds for the line")
    p.add_argument("--back", action="store_true", help="and back along the line in as long again")
    p.add_argument("--name", help="motion name (default: the output file's stem, else 'line')")
    p.add_argument("--out", type=output_path, metavar="MOTION", help="write the motion file (atomically)")
    motion_physics_args(p)


def _orientation(words: list[str]) -> str | tuple[float, float, float]:
    """``--orientation``: ``free``, ``keep`` or a direction of three finite numbers."""
    if len(words) == 1 and words[0] in ("free", "keep"):
        return words[0]
    numbers = [n for n in map(_finite, words) if n is not None]
    if len(words) != 3 or len(numbers) != 3:
        raise InputError(f"expected free, keep or three numbers DX DY DZ, got {' '.join(words)}", "orientation")
    return (numbers[0], numbers[1], numbers[2])


def _finite(word: str) -> float | None:
    """``word`` as a finite number, None if it is not one."""
    import math

    try:
        value = float(word)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def cmd_line(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion line``."""
    from pathlib import Path

    from op2motion.formats.posefile import read_pose
    from op2motion.motion.cartesian import LineRequest
    from op2motion.tasks.motion import line_move_task

    pose = read_pose(args.pose, spec)
    request = LineRequest(args.hand, args.duration, tuple(args.to) if args.to else None,
                          tuple(args.by) if args.by else None, _orientation(args.orientation), args.back)
    name = args.name or (Path(args.out).stem if args.out else "line")
    outputs = motion_outputs(args)
    with physics_progress(args) as on_progress:
        result = line_move_task(pose, request, spec, motion_check(args), name, on_progress)
    return deliver(args, result, outputs)
