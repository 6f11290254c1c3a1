"""``op2motion walk --commands FILE``: a walk steered by a command timeline, planned as it would be while walking,
checked in physics, drawn against the commanded path."""

from __future__ import annotations

import argparse
import math
from typing import Any, Callable

import numpy as np

from op2motion.commands.common import emit, engines_of, progress
from op2motion.errors import CheckFailed, InputError
from op2motion.robot.spec import Spec

#: Flags of ``walk`` that mean nothing with ``--commands`` (the commands set the steps and where they go).
NOT_WITH_COMMANDS = {"steps": "--steps", "target": "--target", "retime": "--retime", "trials": "--trials",
                     "open_loop": "--open-loop", "out": "--out"}


def _refuse_others(args: argparse.Namespace) -> None:
    for dest, flag in NOT_WITH_COMMANDS.items():
        if getattr(args, dest, None):
            raise InputError(f"expected --commands or {flag}, not both (the commands set the steps)", dest)
    if args.action and not args.commands:
        raise InputError("expected --commands with --action (its pages 12/13 are the kicks of a commanded walk)",
                         "action")


def _walk(args: argparse.Namespace, spec: Spec) -> Any:
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import read_commands
    from op2motion.gait.steer import SteerableWalk

    timeline = read_commands(args.commands)
    action = ActionFile.read(args.action) if args.action else None
    return SteerableWalk.make(spec, args.preset, commands=timeline, action=action)


def _commanded(walk: Any) -> dict[str, Any]:
    from op2motion.gait.commands import commanded_path

    timeline = walk.commands
    _, poses = commanded_path(timeline)
    events = [e.event for e in timeline.entries if e.event]
    return {"source": timeline.source, "entries": len(timeline.entries), "duration_s": timeline.duration_s,
            "events": events, "end_pose": {"x_m": round(float(poses[-1, 0]), 4), "y_m": round(float(poses[-1, 1]), 4),
                                           "yaw_deg": round(math.degrees(float(poses[-1, 2])), 2)}}


def _physics(args: argparse.Namespace, walk: Any, spec: Spec, result: dict[str, Any]) -> Any:
    """``--validate``: the walk in physics (``--robust``: over the robustness family)."""
    from op2motion.gait import side_pushes, walk_summary
    from op2motion.gait.robust import commanded_judge, robust_table, walk_badness
    from op2motion.gait.steer import SteerableWalk
    from op2motion.physics import Setup, check, robust_check, robust_summary

    plan = walk.plan
    pushes = side_pushes(args.push) if args.push else None
    if args.robust:
        def fresh() -> Any:
            twin = SteerableWalk(walk.params, spec, walk.feedback, walk.envelope, walk.commands, walk.action)
            twin._plan = plan
            return twin

        with progress(args, "robust", "run") as on_progress:
            family = robust_check(fresh, spec, engines_of(args), commanded_judge, pushes, on_progress=on_progress)
        result["robust"] = robust_summary(family)
        result["robust"]["worst"] = family.worst(walk_badness).member.name
        return family, robust_table(family)
    with progress(args, "physics", "s") as on_progress:
        report = check(walk, spec, engines_of(args), pushes, setup=Setup(keep_track=bool(args.plot)),
                       on_progress=on_progress)
    result["physics"] = walk_summary(report, plan.walk.start_s if plan.walk else 0.0)
    result["fell"] = report.fell
    return report, None


def _figure(walk: Any, report: Any) -> bytes:
    from op2motion.figures.steer import render_steered
    from op2motion.gait.commands import commanded_path
    from op2motion.gait.steer import LEAD_S

    times, commanded = commanded_path(walk.commands)
    rows, n = walk.dry.rows, walk.dry_rows
    planned_t = LEAD_S + np.arange(n) * 0.008
    planned = np.column_stack([rows.numeric["torso_pos"][:n, :2], rows.numeric["plan_yaw"][:n]])
    walked = {}
    if report is not None and hasattr(report, "engines"):
        for engine, r in report.engines.items():
            track = r.run.track
            if track is not None and track.base_pos is not None:
                yaw = np.unwrap(np.arctan2(track.rot[:, 1, 0], track.rot[:, 0, 0]))
                walked[engine] = (track.times, np.column_stack([track.base_pos[:, :2], yaw]))
    return render_steered(commanded, times, planned, planned_t, walked, f"walk --commands {walk.commands.source}")


def commanded_walk(args: argparse.Namespace, spec: Spec, walk_line: Callable[[str, dict[str, Any]], str]) -> int:
    """``walk --commands FILE`` (see the module docstring); ``walk_line`` says one engine's walk in words (``walk``'s
    own)."""
    from op2motion.fileio import OutputSet
    from op2motion.gait.steer import planned_summary

    _refuse_others(args)
    outputs = OutputSet({"plot": args.plot} if args.plot else {})
    walk = _walk(args, spec)
    with progress(args, "plan", "row"):
        summary = planned_summary(walk)
    result: dict[str, Any] = {"preset": walk.params.name, "commands": _commanded(walk), "planned": summary}
    end = summary["end_pose"]
    lines = [f"walk --commands {walk.commands.source}: {len(walk.commands.entries)} entries over "
             f"{walk.commands.duration_s:g} s; planned {summary['steps']} steps, {summary['kicks']} kicks, "
             f"{summary['duration_s']:.1f} s, ending at x {end['x_m']:.3f} m, y {end['y_m']:.3f} m, heading "
             f"{end['yaw_deg']:+.1f}° (ZMP margin >= {summary['zmp_margin_min_m'] * 1000:.1f} mm)"]
    report, table = _physics(args, walk, spec, result) if args.validate else (None, None)
    if table is not None:
        lines.append(table)
    elif report is not None:
        lines += [walk_line(e, s) for e, s in result["physics"]["engines"].items()]
    failed = report is not None and (not report.passed if table is not None else report.fell)
    if args.plot:
        outputs.put("plot", _figure(walk, report))
    written = {} if failed else outputs.commit()
    result["files"] = {k: str(v) for k, v in written.items()}
    lines += [f"  wrote {p}" for p in written.values()]
    emit(args, result, "\n".join(lines))
    if failed:
        raise CheckFailed(f"the commanded walk {'failed in the robustness family' if table else 'fell in physics'}")
    return 0
