"""CLI commands for robot and simulator files: export, import-action."""

from __future__ import annotations

import argparse
import json
from typing import Any

from op2motion.commands.common import add_command, cable_warnings, emit, number, output_path, pose_name, warn, whole
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
    from op2motion.formats.tables import csv_table, webots_motion, webots_warnings

    outputs = OutputSet({"output": args.output})
    poses = [read_pose(p, spec) for p in args.poses]
    if args.format == "action":
        base = ActionFile.read(args.base) if args.base else ActionFile.blank()
        done = base.with_poses(poses, spec, args.page, args.time, args.force)
        written, first = done.action, done.first
        outputs.put("output", written.data)
        text = (f"{len(poses)} pose(s) in pages {first}..{first + len(poses) - 1}" if poses
                else "the base, unchanged")
    else:
        if not poses:
            raise InputError(f"expected at least one pose file for the {args.format} format", "poses")
        render = webots_motion if args.format == "webots" else csv_table
        outputs.put("output", render(poses, spec, args.time))
        text = f"{len(poses)} pose(s)"
    out = outputs.commit()["output"]
    result = {"path": str(out), "format": args.format, "poses": [p.name for p in poses]}
    if args.format == "action" and poses:
        result["pages"] = list(range(first, first + len(poses)))
    warn(args, result, cable_warnings(poses, spec) + (webots_warnings(poses, spec) if args.format == "webots" else []))
    emit(args, result, f"wrote {out}: {text}")
    return 0


def cmd_import_action(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion import-action``."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.action import ActionFile
    from op2motion.formats.posefile import pose_to_json

    if args.out and args.page is None:
        raise InputError("expected --page N with --out")
    outputs = OutputSet({"out": args.out} if args.out else {})
    action = ActionFile.read(args.file)
    if args.page is not None:
        pose = action.pose(args.page, spec, args.name).checked(spec, "page")
        text = pose_to_json(pose, spec)
        if args.out:
            outputs.put("out", text)
            outputs.commit()
        result = {"page": args.page, "pose": json.loads(text), "path": args.out}
        warn(args, result, cable_warnings([pose], spec))
        emit(args, result, f"page {args.page} -> pose {pose.name!r}" + (f", wrote {args.out}" if args.out else ""))
        return 0
    pages = action.pages(spec)
    result = {"pages": [{"index": p.index, "name": p.name, "repeat": p.repeat, "next": p.next,
                         "steps": [{"ticks": {str(k): v for k, v in s.ticks.items()}, "pause": s.pause, "time": s.time}
                                   for s in p.steps]} for p in pages]}
    text = "\n".join(f"{p.index:3d} {p.name:<14} {len(p.steps)} step(s)" + (f" -> page {p.next}" if p.next else "")
                     for p in pages)
    emit(args, result, text)
    return 0
