"""CLI: ``motion line`` (a hand along a straight line, the whole body keeping its balance)."""

from __future__ import annotations

import argparse
from typing import Any

from op2motion.commands.common import add_command, number, output_path
from op2motion.commands.motion_run import finish, motion_physics_args
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

    from op2motion.figures.paths import render_line
    from op2motion.formats.motionfile import motion_to_json
    from op2motion.formats.posefile import read_pose
    from op2motion.motion.cartesian import LineRequest, line_move

    pose = read_pose(args.pose, spec)
    request = LineRequest(args.hand, args.duration, tuple(args.to) if args.to else None,
                          tuple(args.by) if args.by else None, _orientation(args.orientation), args.back)
    move = line_move(pose, request, spec)
    name = args.name or (Path(args.out).stem if args.out else "line")
    motion = move.motion(name)
    trajectory = move.trajectory(motion.p_gain)
    summary = move.summary(spec)
    result: dict[str, Any] = {"name": name, "pose": pose.name, "support": str(pose.support), **summary,
                              "duration_s": round(trajectory.duration_s, 3), "ticks": len(trajectory.goals) - 1,
                              "motion_file": args.out}
    lines = [f"{name}: the {args.hand} hand from {pose.name}, {summary['length_m'] * 1000:.1f} mm in "
             f"{trajectory.duration_s:.3f} s{' and back' if args.back else ''}: off the line <= "
             f"{summary['line_deviation_max_m'] * 1000:.2f} mm, CoM margin >= {summary['com_margin_min_m'] * 1000:.1f} "
             f"mm, fastest joint {summary['joint_speed_joint']} at {summary['joint_speed_max_rad_s']:.2f} rad/s; "
             f"solved {summary['solved']}" + (f" (the arm changes branch first, {summary['reconfigure_s']:.2f} s)"
                                              if summary["reconfigure_s"] else "")]
    title = f"{name}: {args.hand} hand line from {pose.name}"
    return finish(args, spec, trajectory, title, result, lines, lambda verdict: render_line(move, title, verdict),
                  (args.out, motion_to_json(motion, spec, args.out)) if args.out else None)
