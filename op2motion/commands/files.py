"""CLI commands for robot and simulator files: export, import-action."""

from __future__ import annotations

import argparse
from typing import Any

from op2motion.commands.common import add_command, number, output_path, pose_name, whole
from op2motion.commands.deliver import deliver
from op2motion.errors import InputError
from op2motion.formats.actionlayout import NUM_PAGES
from op2motion.formats.tables import MAX_TIME_S
from op2motion.robot.spec import Spec

PAGE = whole(1, NUM_PAGES - 1)


def register(sub: Any) -> None:
    """Add export and import-action."""
    p = add_command(sub, "export", cmd_export, "pose files -> ROBOTIS action file, Webots motion or CSV")
    p.add_argument("poses", nargs="*", metavar="POSE", help="pose files, in order")
    p.add_argument("--format", choices=("action", "webots", "csv"), required=True, help="output format")
    p.add_argument("--base", metavar="FILE", help="action file to start from (default: reset pages)")
    p.add_argument("--page", type=PAGE, help="first page to write (action format; default: the first run of empty "
                                              "pages of the base)")
    p.add_argument("--force", action="store_true", help="overwrite pages of the base that hold actions")
    p.add_argument("--time", type=number(0.0, MAX_TIME_S, "s", open_low=True), default=1.0,
                   help="seconds per pose (default 1.0)")
    p.add_argument("-o", "--output", type=output_path, required=True, metavar="OUT", help="file to write (atomically)")

    p = add_command(sub, "import-action", cmd_import_action,
                    "list the pages of a ROBOTIS action file, or turn one into a pose")
    p.add_argument("file", metavar="FILE", help="motion_4096.bin")
    p.add_argument("--page", type=PAGE, help="page to turn into a pose (its last step)")
    p.add_argument("--out", type=output_path, metavar="POSE", help="write that pose file (with --page)")
    p.add_argument("--name", type=pose_name, help="pose name (default: the page name)")


def cmd_export(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion export``."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.action import ActionFile
    from op2motion.formats.posefile import read_pose
    from op2motion.tasks.files import PageWrite, export_poses

    outputs = OutputSet({"output": args.output})
    poses = [read_pose(p, spec) for p in args.poses]
    pages = PageWrite(ActionFile.read(args.base) if args.base and args.format == "action" else None, args.page,
                      args.force)
    return deliver(args, export_poses(poses, spec, args.format, outputs.paths["output"], args.time, pages), outputs,
                   "none")


def cmd_import_action(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion import-action``."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.action import ActionFile
    from op2motion.tasks.files import import_page, list_pages

    if args.out and args.page is None:
        raise InputError("expected --page N with --out")
    outputs = OutputSet({"out": args.out} if args.out else {})
    action = ActionFile.read(args.file)
    if args.page is None:
        return deliver(args, list_pages(action, spec), outputs, "none")
    result = import_page(action, args.page, spec, args.name, outputs.paths.get("out"), args.out)
    return deliver(args, result, outputs, "none")
