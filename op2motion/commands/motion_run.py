"""What ``motion play``, ``motion plan`` and ``motion line`` share: the physics flags, and the finish (checks along
the trajectory, physics, plot, CSV, the report)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any, Callable

from op2motion.commands.common import emit, engines_of, output_path, physics_args, png_path, progress
from op2motion.errors import CheckFailed
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.motion.trajectory import Trajectory
    from op2motion.physics import CheckReport


def motion_physics_args(p: argparse.ArgumentParser) -> None:
    """--validate, --engine, --push, --plot and --csv."""
    physics_args(p, True, "with --validate: push the torso N newtons for 0.1 s halfway through (four directions)")
    p.add_argument("--plot", type=png_path, metavar="PNG", help="q, q̇, q̈ per joint and the CoM/ZMP/CoP tracks")
    p.add_argument("--csv", type=output_path, metavar="CSV", help="the goals every 8 ms as CSV")


def _physics(args: argparse.Namespace, trajectory: Trajectory, spec: Spec) -> CheckReport | None:
    """With ``--validate``: the trajectory's goals played in physics in the engines asked for."""
    from op2motion.physics import Pushes, check

    if not args.validate:
        return None
    with progress(args, "physics", "s") as on_progress:
        return check(trajectory.schedule(spec), spec, engines_of(args), Pushes(args.push) if args.push else None,
                     on_progress=on_progress)


def _physics_lines(report: CheckReport) -> list[str]:
    lines = []
    for engine, e in report.engines.items():
        m = e.run.motion
        worst = f"{m.worst_torque.torque_nm:.2f} N·m at {m.worst_torque.joint}" if m else "-"
        tracking = max(m.tracking_max_deg.values()) if m else 0.0
        lines.append(f"  {engine}: {e.run.summary()}; tracking error <= {tracking:.1f}°, worst torque {worst}")
    return lines


def goals_beyond_range(trajectory: Trajectory, spec: Spec) -> str | None:
    """Where goals leave a joint's mechanical range (the servo would drive into its stop), in words; None if never.
    """
    import numpy as np

    from op2motion.robot.joints import LIMIT_SLACK_RAD, joint_range

    lower, upper = (np.array([joint_range(j, "mechanical")[k] for j in spec.joints]) for k in (0, 1))
    beyond = np.maximum(lower - trajectory.goals, trajectory.goals - upper)
    row, joint = np.unravel_index(int(np.argmax(beyond)), beyond.shape)
    if beyond[row, joint] <= LIMIT_SLACK_RAD:
        return None
    return (f"the goals drive {spec.joint_names[joint]} to {np.degrees(trajectory.goals[row, joint]):.0f}° at "
            f"{row * trajectory.dt:.2f} s, outside its mechanical range ({np.degrees(lower[joint]):.0f}.."
            f"{np.degrees(upper[joint]):.0f}°)")


def _verdict(engine: Any) -> str:
    """One engine's verdict in words: its reasons, or stable, and the pushes it did not stand."""
    words = "stable" if engine.run.stable else ", ".join(engine.run.reasons)
    failed = [f"{p.force_n:g} N {p.direction}" for p in engine.pushes if not p.stable]
    return words + (f"; fails when pushed {', '.join(failed)}" if failed else "")


def finish(args: argparse.Namespace, spec: Spec, trajectory: Trajectory, title: str, result: dict[str, Any],
            lines: list[str], figure: Callable[[str], bytes] | None = None,
            motion_file: tuple[str, str] | None = None) -> int:
    """Checks, physics, plot and CSV common to play, plan and line; raises CheckFailed (exit 1) when physics says
    no, having written nothing. ``figure`` draws the plot from the verdict's words (default: the joint curves and
    balance tracks); ``motion_file`` (path, text) is written with the other outputs."""
    from op2motion.figures.motion import render_motion
    from op2motion.fileio import OutputSet
    from op2motion.formats.tables import goals_csv
    from op2motion.motion.checks import check_trajectory, in_sole_frame

    paths = {k: getattr(args, k) for k in ("plot", "csv") if getattr(args, k)}
    outputs = OutputSet({**paths, **({"out": motion_file[0]} if motion_file else {})})
    unreachable = goals_beyond_range(trajectory, spec)
    if unreachable:
        raise CheckFailed(f"{title}: {unreachable}")
    report = _physics(args, trajectory, spec)
    checks = check_trajectory(trajectory, spec)      # one frame, the fixed foot's, with or without physics
    result["checks"] = checks.summary()
    if report is not None:
        result["physics"] = {"engines": {e: r.as_dict() for e, r in report.engines.items()}, "agree": report.agree,
                             "stable": report.agree and report.stable and report.pushes_stood}
    if args.plot:
        verdict = "not checked in physics" if report is None else " | ".join(
            f"{e}: {_verdict(r)}" for e, r in report.engines.items())
        cop = None
        if report is not None and report.run.motion:
            cop = in_sole_frame(report.run.motion.cop_track, trajectory.goals[0], report.run.flat_foot,
                                checks.fixed_foot, spec)
        outputs.put("plot", figure(verdict) if figure else render_motion(trajectory, checks, spec, title, cop,
                                                                          verdict))
    if args.csv:
        outputs.put("csv", goals_csv(trajectory.times, trajectory.goals, trajectory.supports, spec))
    if motion_file:
        outputs.put("out", motion_file[1])
    problem = None if report is None else report.problem("does not get through")
    written = {} if problem else outputs.commit()
    result["files"] = {k: str(v) for k, v in written.items()}
    s = checks.summary()
    lines.append(f"  checks: least clearance {s['min_clearance_m'] * 1000:.1f} mm "
                 f"({' / '.join(s['min_clearance_links'])}), ZMP margin >= {s['zmp_margin_min_m'] * 1000:.1f} mm, "
                 f"torque <= {s['torque_ratio_max']:.0%} of available ({s['torque_joint']})")
    lines += ([] if report is None else _physics_lines(report)) + [f"  wrote {p}" for p in written.values()]
    emit(args, result, "\n".join(lines))
    if problem:
        raise CheckFailed(f"{title}: {problem}")
    return 0
