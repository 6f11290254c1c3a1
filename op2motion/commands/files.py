"""CLI commands for robot and simulator files: export, import-action."""

from __future__ import annotations

import argparse
import json


from ..cli import emit
from ..errors import InputError
from ..spec import Spec


def cmd_export(args: argparse.Namespace, spec: Spec) -> int:
    from ..export.action import read_action, write_poses
    from ..export.library import read_pose
    from ..export.tables import write_table

    poses = [read_pose(p, spec) for p in args.poses]
    if args.format == "action":
        base = read_action(args.base, spec) if args.base else None
        out = write_poses(poses, spec, args.output, args.page, args.time, base)
        text = (f"wrote {out}: {len(poses)} pose(s) in pages {args.page}..{args.page + len(poses) - 1}"
                if poses else f"wrote {out}: the base, unchanged")
    else:
        if not poses:
            raise InputError(f"export --format {args.format}: expected at least one pose file")
        out = write_table(args.format, poses, spec, args.output, args.time)
        text = f"wrote {out}: {len(poses)} pose(s)"
    emit(args, {"path": str(out), "format": args.format, "poses": [p.name for p in poses]}, text)
    return 0


def cmd_import_action(args: argparse.Namespace, spec: Spec) -> int:
    from ..export.action import list_pages, page_to_pose, read_action, requested_page
    from ..export.library import pose_to_json, write_pose

    data = read_action(args.file, spec)
    if args.page is not None:
        pose = page_to_pose(requested_page(data, args.page, spec, args.file), spec, args.name)
        if args.out:
            write_pose(pose, args.out, spec)
        doc = json.loads(pose_to_json(pose, spec))
        emit(args, {"page": args.page, "pose": doc, "path": args.out},
              f"page {args.page} -> pose {pose.name!r}" + (f", wrote {args.out}" if args.out else ""))
        return 0
    if args.out:
        raise InputError("--out needs --page N")
    pages = list_pages(data, spec, args.file)
    result = {"pages": [{"index": p.index, "name": p.name, "repeat": p.repeat, "next": p.next,
                         "steps": [{"ticks": {str(k): v for k, v in s.ticks.items()}, "pause": s.pause, "time": s.time}
                                   for s in p.steps]} for p in pages]}
    text = "\n".join(f"{p.index:3d} {p.name:<14} {len(p.steps)} step(s)" + (f" -> page {p.next}" if p.next else "")
                     for p in pages)
    emit(args, result, text)
    return 0
