"""CLI commands for motions: ``motion play`` (action pages), ``motion plan`` (pose sequences), ``motion export``."""

from __future__ import annotations

import argparse
from typing import Any, Sequence, TypeVar

from op2motion.commands.common import add_command, number, output_path, whole
from op2motion.commands.deliver import deliver
from op2motion.commands.motion_run import motion_check, motion_outputs, motion_physics_args, physics_progress
from op2motion.errors import InputError
from op2motion.formats.actionlayout import NUM_PAGES
from op2motion.formats.motionfile import PLANNERS, PROFILES
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

PAGE = whole(1, NUM_PAGES - 1)
T = TypeVar("T")
SECONDS = number(0.0, 60.0, "s")


def _planner_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--planner", choices=PLANNERS, default="rrt",
                   help="where the straight line between two poses collides: plan around it in joint space "
                        "with our RRT-Connect (rrt, default) or OMPL's (ompl: the ompl extra), or refuse (none)")
    p.add_argument("--seed", type=whole(0, 2 ** 31 - 1), default=0, help="seed of the path planner (default 0)")


def register(sub: Any) -> None:
    """Add ``motion play|plan|export``."""
    from op2motion.commands.common import Parser

    top = sub.add_parser("motion", help="play action pages, plan pose-to-pose motions, export them",
                         description="Motions: action pages played as the robot plays them, planned pose "
                                     "sequences, both checked along the way and in physics.")
    inner = top.add_subparsers(dest="motion_command", metavar="ACTION", required=True, parser_class=Parser,
                               help="play, plan or export")
    p = add_command(inner, "play", cmd_play, "play an action page tick for tick (8 ms) as the OP2 framework does")
    p.add_argument("file", metavar="FILE", help="action file (motion_4096.bin)")
    p.add_argument("--page", type=PAGE, required=True, help="page to play")
    p.add_argument("--start", metavar="POSE", help="pose file the robot stands in (default: page 1's last step)")
    motion_physics_args(p)
    p = add_command(inner, "plan", cmd_plan, "plan a motion through poses (or a motion file) and check it")
    p.add_argument("poses", nargs="+", metavar="POSE", help="pose files in order, or one motion file")
    p.add_argument("--durations", type=SECONDS, nargs="+", metavar="S",
                   help="seconds to reach each pose after the first (one value: for all)")
    p.add_argument("--pauses", type=SECONDS, nargs="+", metavar="S", help="seconds to hold each pose (default 0)")
    p.add_argument("--support", choices=[s.value for s in Support], nargs="+",
                   help="support of each pose (default: the pose files')")
    p.add_argument("--profile", choices=PROFILES, default=None, help="quintic (default) or the "
                                                                                 "robot's trapezoid")
    p.add_argument("--name", help="motion name (default: the output file's stem)")
    p.add_argument("--out", type=output_path, metavar="MOTION", help="write the motion file (atomically)")
    _planner_args(p)
    motion_physics_args(p)
    p = add_command(inner, "export", cmd_export, "a motion file -> action pages, Webots motion or CSV")
    p.add_argument("motion", metavar="MOTION", help="motion file (schema op2motion.motion/1)")
    p.add_argument("--format", choices=("action", "webots", "csv"), required=True, help="output format")
    p.add_argument("--base", metavar="FILE", help="action file to add the pages to (default: reset pages)")
    p.add_argument("--page", type=PAGE, help="first page (default: the first run of empty pages)")
    p.add_argument("--force", action="store_true", help="overwrite pages that hold actions")
    p.add_argument("-o", "--output", type=output_path, required=True, metavar="OUT", help="file to write")
    _planner_args(p)
    from op2motion.commands.motion_line import register_line

    register_line(inner)


def cmd_play(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion play``."""
    from op2motion.formats.action import ActionFile
    from op2motion.formats.posefile import read_pose
    from op2motion.tasks.motion import play_page_task

    action = ActionFile.read(args.file)
    start = read_pose(args.start, spec) if args.start else None
    outputs = motion_outputs(args)
    with physics_progress(args) as on_progress:
        return deliver(args, play_page_task(action, args.page, spec, motion_check(args), start, on_progress), outputs)


def _broadcast(values: Sequence[T] | None, n: int, default: T | None, flag: str) -> list[T]:
    if values is None:
        if default is None:
            raise InputError(f"expected {flag} for the {n} pose(s) after the first", flag.lstrip("-"))
        return [default] * n
    if len(values) == 1:
        return list(values) * n
    if len(values) != n:
        raise InputError(f"expected 1 or {n} values, got {len(values)}", flag.lstrip("-"))
    return list(values)


def _motion_from_args(args: argparse.Namespace, spec: Spec) -> Any:
    from pathlib import Path

    from op2motion.formats.motionfile import is_motion_file, motion_of, read_motion, rebased, relative_source
    from op2motion.formats.posefile import read_pose
    from op2motion.robot.pose import Pose

    if len(args.poses) == 1 and is_motion_file(args.poses[0]):
        if args.durations or args.pauses or args.support:
            raise InputError("a motion file carries its own durations, pauses and supports", "durations")
        motion = read_motion(args.poses[0], spec)
        if args.out:
            motion = rebased(motion, args.poses[0], args.out)
        return motion if args.profile is None else type(motion)(motion.name, motion.steps, args.profile,
                                                                motion.p_gain)
    poses = [read_pose(p, spec) for p in args.poses]
    if len(poses) < 2:
        raise InputError(f"expected at least two poses, got {len(poses)}", "poses")
    if args.support:
        supports: list[str] = _broadcast(args.support, len(poses), None, "--support")
        poses = [Pose(p.name, Support.of(s), p.servo, p.metrics, p.provenance) for p, s in zip(poses, supports)]
    durations = _broadcast(args.durations, len(poses) - 1, None, "--durations")
    pauses = _broadcast(args.pauses, len(poses), 0.0, "--pauses")
    where = args.out or "motion.json"
    sources = [relative_source(p, where) for p in args.poses]
    name = args.name if args.name is not None else (Path(args.out).stem if args.out else "motion")
    return motion_of(poses, sources, durations, pauses, name, args.profile or "quintic")


def cmd_plan(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion plan``."""
    from op2motion.tasks.motion import plan_motion_task

    motion = _motion_from_args(args, spec)
    outputs = motion_outputs(args)
    with physics_progress(args) as on_progress:
        result = plan_motion_task(motion, spec, motion_check(args), args.planner, args.seed, on_progress)
    return deliver(args, result, outputs)


def cmd_export(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion export``."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.action import ActionFile
    from op2motion.formats.motionfile import read_motion
    from op2motion.tasks.files import PageWrite, export_motion

    motion = read_motion(args.motion, spec)
    outputs = OutputSet({"output": args.output})
    pages = PageWrite(ActionFile.read(args.base) if args.base and args.format == "action" else None, args.page,
                      args.force)
    result = export_motion(motion, spec, args.format, outputs.paths["output"], pages, args.planner, args.seed)
    return deliver(args, result, outputs, "none")
