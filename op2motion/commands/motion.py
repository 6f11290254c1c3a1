"""CLI commands for motions: ``motion play`` (action pages), ``motion plan`` (pose sequences), ``motion export``."""

from __future__ import annotations

import argparse
from typing import Any, Sequence

from op2motion.commands.common import add_command, emit, number, output_path, progress_enabled, warn, whole
from op2motion.errors import CheckFailed, InputError
from op2motion.formats.actionlayout import NUM_PAGES
from op2motion.formats.motionfile import PROFILES
from op2motion.physics import ENGINES, MAX_PUSH_N
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

PAGE = whole(1, NUM_PAGES - 1)
SECONDS = number(0.0, 60.0, "s")


def _physics_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--validate", action="store_true", help="play the goals into the servo model in physics")
    p.add_argument("--engine", choices=(*ENGINES, "both"), default="pybullet", help="physics engine (default "
                                                                                     "pybullet)")
    p.add_argument("--push", type=number(0.0, MAX_PUSH_N, "N"), default=0.0, metavar="N",
                   help="with --validate: push the torso N newtons for 0.1 s halfway through (four directions)")
    p.add_argument("--plot", type=output_path, metavar="PNG", help="q, q̇, q̈ per joint and the CoM/ZMP/CoP tracks")
    p.add_argument("--csv", type=output_path, metavar="CSV", help="the goals every 8 ms as CSV")


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
    _physics_args(p)
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
    _physics_args(p)
    p = add_command(inner, "export", cmd_export, "a motion file -> action pages, Webots motion or CSV")
    p.add_argument("motion", metavar="MOTION", help="motion file (schema op2motion.motion/1)")
    p.add_argument("--format", choices=("action", "webots", "csv"), required=True, help="output format")
    p.add_argument("--base", metavar="FILE", help="action file to add the pages to (default: reset pages)")
    p.add_argument("--page", type=PAGE, help="first page (default: the first run of empty pages)")
    p.add_argument("--force", action="store_true", help="overwrite pages that hold actions")
    p.add_argument("-o", "--output", type=output_path, required=True, metavar="OUT", help="file to write")


def _validate(args: argparse.Namespace, trajectory: Any, spec: Spec) -> tuple[dict[str, Any] | None, dict[str, Any]]:
    """With ``--validate``: the physics result for the JSON and the verdict of each engine."""
    from tqdm import tqdm

    from op2motion.physics import MOTION_HOLD_S, MOTION_SETTLE_S, RAMP_S, TIME_STEP_S, validate_motion

    if not args.validate:
        return None, {}
    engines = ENGINES if args.engine == "both" else (args.engine,)
    seconds = RAMP_S + MOTION_SETTLE_S + trajectory.duration_s + MOTION_HOLD_S
    steps = int(round(seconds / TIME_STEP_S)) * len(engines) * (1 + 4 * (args.push > 0))
    verdicts = {}
    with tqdm(total=steps, desc="physics", unit="step", leave=False, disable=not progress_enabled(args)) as bar:
        for engine in engines:
            verdicts[engine] = validate_motion(trajectory.goals, trajectory.p_gains, trajectory.supports, spec,
                                               trajectory.dt, engine, args.push, on_step=bar.update)
    agree = len({v.stable for v in verdicts.values()}) == 1
    first = next(iter(verdicts.values()))
    return {"engines": {e: v.as_dict() for e, v in verdicts.items()}, "agree": agree,
            "stable": agree and first.stable and all(p.stable for v in verdicts.values() for p in v.pushes)}, verdicts


def _finish(args: argparse.Namespace, spec: Spec, trajectory: Any, title: str, result: dict[str, Any],
            lines: list[str]) -> int:
    """Checks, physics, plot and CSV common to play and plan; raises CheckFailed (exit 1) when physics says no."""
    from op2motion.figures.motion import render_motion
    from op2motion.fileio import OutputSet
    from op2motion.formats.tables import goals_csv
    from op2motion.motion.checks import check_trajectory

    outputs = OutputSet({k: getattr(args, k) for k in ("plot", "csv") if getattr(args, k)})
    physics, verdicts = _validate(args, trajectory, spec)
    flat = next(iter(verdicts.values())).flat_foot if verdicts else None      # the physics world's floor frame
    checks = check_trajectory(trajectory, spec, foot=flat)
    result["checks"] = checks.summary()
    if physics:
        result["physics"] = physics
    if args.plot:
        first = next(iter(verdicts.values()), None)
        verdict = "not checked in physics" if first is None else " | ".join(
            f"{e}: {'stable' if v.stable else ', '.join(v.reasons)}" for e, v in verdicts.items())
        outputs.put("plot", render_motion(trajectory, checks, spec, title, first.cop_track if first else None,
                                          verdict))
    if args.csv:
        outputs.put("csv", goals_csv(trajectory.times, trajectory.goals, trajectory.supports, spec))
    written = outputs.commit()
    result["files"] = {k: str(v) for k, v in written.items()}
    s = checks.summary()
    pair = " / ".join(s["min_clearance_links"])
    lines.append(f"  checks: least clearance {s['min_clearance_m'] * 1000:.1f} mm ({pair}), "
                 f"ZMP margin >= {s['zmp_margin_min_m'] * 1000:.1f} mm, torque <= {s['torque_ratio_max']:.0%} of "
                 f"available ({s['torque_joint']})")
    for engine, v in verdicts.items():
        worst = v.motion_worst_torque or {}
        lines.append(f"  {engine}: {v.summary()}; tracking error <= {max(v.tracking_max_deg.values()):.1f}°, "
                     f"worst torque {worst.get('torque_nm', 0):.2f} N·m at {worst.get('joint', '-')}")
    lines += [f"  wrote {p}" for p in written.values()]
    emit(args, result, "\n".join(lines))
    if physics and not physics["agree"]:
        raise CheckFailed(f"{title}: the engines disagree (" + ", ".join(
            f"{e}: {'stands' if v.stable else v.reason}" for e, v in verdicts.items()) + ")")
    if physics and not physics["stable"]:
        bad = next(v for v in verdicts.values() if not v.stable or any(not p.stable for p in v.pushes))
        raise CheckFailed(f"{title} does not get through in physics: " + (bad.reason if not bad.stable else "a push"))
    return 0


def cmd_play(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion play``."""
    from op2motion.formats.action import page_to_pose, read_action, requested_page
    from op2motion.formats.posefile import read_pose
    from op2motion.motion.player import IDS, play
    from op2motion.motion.trajectory import from_playback
    from op2motion.robot.joints import servo_to_ticks

    data = read_action(args.file)
    page = requested_page(data, args.page, spec, args.file)
    start = read_pose(args.start, spec) if args.start else page_to_pose(requested_page(data, 1, spec, args.file),
                                                                         spec)
    by_id = {j.id: int(t) for j, t in zip(spec.joints, servo_to_ticks(start.servo, spec))}
    playback = play(data, args.page, [by_id[i] for i in IDS])
    trajectory = from_playback(playback, spec, page.name)
    result: dict[str, Any] = {"page": args.page, "name": page.name, "start": start.name, "ticks": playback.calls,
                              "duration_s": round(playback.calls * trajectory.dt, 3),
                              "pages_played": list(playback.pages), "ids": list(IDS),
                              "goals": playback.goals.astype(int).tolist()}
    lines = [f"page {args.page} ({page.name}) from {start.name}: {playback.calls} ticks, "
             f"{playback.calls * trajectory.dt:.3f} s, pages {' -> '.join(map(str, playback.pages))}"]
    return _finish(args, spec, trajectory, f"page {args.page} ({page.name})", result, lines)


def _broadcast(values: Sequence[float] | None, n: int, default: float | None, flag: str) -> list[float]:
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

    from op2motion.formats.motionfile import is_motion_file, motion_of, read_motion, relative_source
    from op2motion.formats.posefile import read_pose
    from op2motion.robot.pose import Pose

    if len(args.poses) == 1 and is_motion_file(args.poses[0]):
        if args.durations or args.pauses or args.support:
            raise InputError("a motion file carries its own durations, pauses and supports", "durations")
        motion = read_motion(args.poses[0], spec)
        return motion if args.profile is None else type(motion)(motion.name, motion.steps, args.profile,
                                                                motion.p_gain)
    poses = [read_pose(p, spec) for p in args.poses]
    if len(poses) < 2:
        raise InputError(f"expected at least two poses, got {len(poses)}", "poses")
    if args.support:
        supports = _broadcast(args.support, len(poses), None, "--support")      # type: ignore[arg-type]
        poses = [Pose(p.name, s, p.servo, p.metrics, p.provenance) for p, s in zip(poses, supports)]
    durations = _broadcast(args.durations, len(poses) - 1, None, "--durations")
    pauses = _broadcast(args.pauses, len(poses), 0.0, "--pauses")
    where = args.out or "motion.json"
    sources = [relative_source(p, where) for p in args.poses]
    name = args.name or (Path(args.out).stem if args.out else "motion")
    return motion_of(poses, sources, durations, pauses, name, args.profile or "quintic")


def waypoints_of(motion: Any) -> list[Any]:
    """The planner's waypoints of a motion file's steps."""
    from op2motion.motion.waypoint import Waypoint

    return [Waypoint(s.pose.name, s.pose.servo, s.duration_s, s.pause_s, s.pose.support) for s in motion.steps]


def cmd_plan(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion plan``."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.motionfile import motion_to_json
    from op2motion.motion.checks import require_clear
    from op2motion.motion.planner import plan

    motion = _motion_from_args(args, spec)
    trajectory = plan(waypoints_of(motion), spec, motion.profile, motion.p_gain)
    require_clear(trajectory, spec)
    if args.out:
        outputs = OutputSet({"out": args.out})
        outputs.put("out", motion_to_json(motion, spec, args.out))
        outputs.commit()
    result: dict[str, Any] = {"name": motion.name, "profile": motion.profile, "ticks": len(trajectory.goals) - 1,
                              "duration_s": round(trajectory.duration_s, 3), "segments": list(trajectory.segment_names),
                              "notes": list(trajectory.notes), "motion_file": args.out}
    warn(result, list(trajectory.notes))
    lines = [f"{motion.name}: {len(motion.steps)} poses, {trajectory.duration_s:.3f} s ({motion.profile})"
             + (f", wrote {args.out}" if args.out else "")]
    return _finish(args, spec, trajectory, motion.name, result, lines)


def cmd_export(args: argparse.Namespace, spec: Spec) -> int:
    """``op2motion motion export``."""
    from op2motion.fileio import OutputSet
    from op2motion.formats.action import check_pages_free, first_empty_run, read_action
    from op2motion.formats.actionlayout import PAGE_SIZE, check_file, reset_file
    from op2motion.formats.motionfile import read_motion
    from op2motion.formats.tables import goals_csv, webots_motion, webots_warnings
    from op2motion.motion.checks import require_clear
    from op2motion.motion.planner import action_pages, plan
    from op2motion.robot.pose import Pose

    motion = read_motion(args.motion, spec)
    waypoints = waypoints_of(motion)
    outputs = OutputSet({"output": args.output})
    result: dict[str, Any] = {"name": motion.name, "format": args.format}
    if args.format == "action":
        data = bytearray(read_action(args.base) if args.base else reset_file())
        check_file(bytes(data), "base")
        pages, notes = action_pages(waypoints, spec, motion.name, 1, motion.p_gain)
        first = first_empty_run(bytes(data), len(pages)) if args.page is None else args.page
        check_pages_free(bytes(data), first, len(pages), args.force)
        pages, notes = action_pages(waypoints, spec, motion.name, first, motion.p_gain)
        for k, page in enumerate(pages):
            data[(first + k) * PAGE_SIZE:(first + k + 1) * PAGE_SIZE] = page
        outputs.put("output", bytes(data))
        result["pages"] = list(range(first, first + len(pages)))
        text = f"pages {first}..{first + len(pages) - 1} (play page {first})"
    else:
        trajectory = plan(waypoints, spec, motion.profile, motion.p_gain)
        require_clear(trajectory, spec)
        notes = list(trajectory.notes)
        if args.format == "csv":
            outputs.put("output", goals_csv(trajectory.times, trajectory.goals, trajectory.supports, spec))
        else:
            rows = [Pose(f"t{k}", "double", g, {}, {}) for k, g in enumerate(trajectory.goals)]
            outputs.put("output", webots_motion(rows, spec, times=list(trajectory.times)))
            notes += webots_warnings([s.pose for s in motion.steps], spec)
        text = f"{len(trajectory.goals)} rows every {trajectory.dt * 1000:.0f} ms"
    out = outputs.commit()["output"]
    result["path"] = str(out)
    warn(result, notes)
    emit(args, result, f"wrote {out}: {motion.name}, {text}")
    return 0

