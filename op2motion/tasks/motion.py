"""The motion tasks: play an action page, plan a motion through poses, move a hand in a straight line; each checked
along its trajectory and, when asked, in physics (:func:`check_motion`), each returning a
:class:`~.result.TaskResult`.

A trajectory whose goals leave a joint's mechanical range is refused before any check (the servo would drive into
its stop); physics that says no (a fall, a push not stood, engines that disagree) is a result with ``ok`` False and
the phrase why; the figure, the CSV of the goals and the motion file are the result's outputs, for the caller to
write when ``ok``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

from op2motion.robot.spec import Spec
from op2motion.tasks.progress import Progress
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile
    from op2motion.formats.motionfile import PlannerName
    from op2motion.motion.cartesian import LineMove, LineRequest
    from op2motion.motion.checks import MotionChecks
    from op2motion.motion.trajectory import Trajectory
    from op2motion.physics import Ball, CheckReport, EngineName
    from op2motion.robot.pose import Pose



@dataclass(frozen=True)
class CheckedMotion:
    """A motion checked: its ``trajectory`` (goals every 8 ms), the ``checks`` along it (clearance, ZMP, torque),
    and its physics ``report`` (None: not checked in physics)."""

    trajectory: Trajectory
    checks: MotionChecks
    report: CheckReport | None


@dataclass(frozen=True)
class MotionCheck:
    """How a motion is checked and what it writes: physics (``validate``, in ``engines``, pushed ``push_n`` [N]
    halfway through when above 0, a ``ball`` on the floor: what the motion does to it is reported), and the outputs
    asked for (``plot`` PNG, ``csv`` of the goals, ``motion_file`` path for the motion file; None: not asked)."""

    validate: bool = False
    engines: tuple[EngineName, ...] = ("pybullet",)
    push_n: float = 0.0
    plot: str | None = None
    csv: str | None = None
    motion_file: str | None = None
    ball: Ball | None = None


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


def _physics_lines(report: CheckReport) -> list[str]:
    lines = []
    for engine, e in report.engines.items():
        m = e.run.motion
        worst = f"{m.worst_torque.torque_nm:.2f} N·m at {m.worst_torque.joint}" if m else "-"
        tracking = max(m.tracking_max_deg.values()) if m else 0.0
        lines.append(f"  {engine}: {e.run.summary()}; tracking error <= {tracking:.1f}°, worst torque {worst}")
        if e.run.ball is not None:
            lines.append(f"  {engine}: {e.run.ball.describe()}")
    return lines


@dataclass(frozen=True)
class Told:
    """What a motion task says about its trajectory before the checks: its ``title`` (in the problem's phrase and
    the figure), its figures (``data``) and its ``lines`` for a person."""

    title: str
    data: dict[str, Any]
    lines: list[str]


def check_motion(trajectory: Trajectory, spec: Spec, how: MotionCheck, told: Told,
                 figure: Callable[[str], bytes] | None = None, motion_text: str | None = None,
                 on_progress: Progress | None = None) -> TaskResult[CheckedMotion]:
    """A trajectory checked (its goals within range, clearance, ZMP and torque along it, physics when asked), what
    the task ``told`` completed by the checks. ``figure`` draws the plot from the verdict's words (default: the joint
    curves and the balance tracks); ``motion_text`` is the motion file."""
    title, data, lines = told.title, told.data, told.lines
    from op2motion.figures.motion import render_motion
    from op2motion.formats.tables import goals_csv
    from op2motion.motion.checks import check_trajectory, in_sole_frame
    from op2motion.physics import Pushes, Setup, check

    unreachable = goals_beyond_range(trajectory, spec)
    if unreachable:
        return TaskResult.refused(f"{title}: {unreachable}")
    report = None
    if how.validate:
        report = check(trajectory.schedule(spec), spec, how.engines, Pushes(how.push_n) if how.push_n else None,
                       setup=Setup(ball=how.ball), on_progress=on_progress)
    checks = check_trajectory(trajectory, spec)      # one frame, the fixed foot's, with or without physics
    data = {**data, "checks": checks.summary()}
    if report is not None:
        data["physics"] = {"engines": {e: r.as_dict() for e, r in report.engines.items()}, "agree": report.agree,
                           "stable": report.agree and report.stable and report.pushes_stood}
    outputs: dict[str, Output] = {}
    if how.plot:
        verdict = "not checked in physics" if report is None else " | ".join(
            f"{e}: {_verdict(r)}" for e, r in report.engines.items())
        cop = None
        if report is not None and report.run.motion:
            cop = in_sole_frame(report.run.motion.cop_track, trajectory.goals[0], report.run.flat_foot,
                                checks.fixed_foot, spec)
        png = figure(verdict) if figure else render_motion(trajectory, checks, spec, title, cop, verdict)
        outputs["plot"] = Output(how.plot, png)
    if how.csv:
        outputs["csv"] = Output(how.csv, goals_csv(trajectory.times, trajectory.goals, trajectory.supports, spec))
    if how.motion_file and motion_text is not None:
        outputs["out"] = Output(how.motion_file, motion_text)
    s = checks.worst()
    lines = [*lines, f"  checks: least clearance {s.min_clearance_m * 1000:.1f} mm "
             f"({' / '.join(s.min_clearance_links)}), ZMP margin >= {s.zmp_margin_min_m * 1000:.1f} mm, "
             f"torque <= {s.torque_ratio_max:.0%} of available ({s.torque_joint})",
             *([] if report is None else _physics_lines(report))]
    problem = None if report is None else report.problem("does not get through")
    return TaskResult(problem is None, None if problem is None else f"{title}: {problem}", None, outputs,
                      {**data, "files": {}}, tuple(lines), value=CheckedMotion(trajectory, checks, report))


def _chain(pages: list[int]) -> str:
    """The pages played, repeats folded: ``3 -> 4 x5 -> 6``."""
    runs: list[list[int]] = []
    for p in pages:
        if runs and runs[-1][0] == p:
            runs[-1][1] += 1
        else:
            runs.append([p, 1])
    return " -> ".join(f"{p} x{n}" if n > 1 else str(p) for p, n in runs)


def play_page_task(action: ActionFile, page: int, spec: Spec, how: MotionCheck, start: Pose | None = None,
              on_progress: Progress | None = None) -> TaskResult[CheckedMotion]:
    """``motion play``: action page ``page`` played tick for tick as the framework does, from ``start`` (default:
    page 1's last step, the stock init pose), checked (:func:`check_motion`)."""
    from op2motion.motion.pipeline import play_page
    from op2motion.motion.player import IDS

    played = play_page(action, page, spec, start)
    playback, name, duration = played.playback, played.page.name, played.trajectory.duration_s
    data = {"page": page, "name": name, "start": played.start.name, "ticks": playback.calls,
            "duration_s": round(duration, 3), "pages_played": list(playback.pages), "ids": list(IDS),
            "goals": playback.goals.astype(int).tolist()}
    lines = [f"page {page} ({name}) from {played.start.name}: {playback.calls} ticks, {duration:.3f} s, pages "
             f"{_chain(list(playback.pages))}"]
    return check_motion(played.trajectory, spec, how, Told(f"page {page} ({name})", data, lines),
                        on_progress=on_progress)


def plan_motion_task(motion: Any, spec: Spec, how: MotionCheck, planner: PlannerName = "rrt", seed: int = 0,
                on_progress: Progress | None = None) -> TaskResult[CheckedMotion]:
    """``motion plan``: ``motion`` (a :class:`~op2motion.formats.motionfile.Motion`) planned (weight shifts, lifts,
    segments around collisions with ``planner`` seeded by ``seed``), checked (:func:`check_motion`); its notes are
    the result's warnings, the motion file its ``out`` output when ``how.motion_file`` names one."""
    from op2motion.formats.motionfile import motion_to_json
    from op2motion.motion.pipeline import plan_motion

    trajectory = plan_motion(motion, spec, planner, seed)
    data = {"name": motion.name, "profile": motion.profile, "ticks": len(trajectory.goals) - 1,
            "duration_s": round(trajectory.duration_s, 3), "segments": list(trajectory.segment_names),
            "notes": list(trajectory.notes), "motion_file": how.motion_file}
    lines = [f"{motion.name}: {len(motion.steps)} poses, {trajectory.duration_s:.3f} s ({motion.profile})"]
    text = motion_to_json(motion, spec, how.motion_file) if how.motion_file else None
    result = check_motion(trajectory, spec, how, Told(motion.name, data, lines), motion_text=text,
                          on_progress=on_progress)
    return result.with_warnings(tuple(trajectory.notes))


def line_move_task(pose: Pose, request: LineRequest, spec: Spec, how: MotionCheck, name: str = "line",
              on_progress: Progress | None = None) -> TaskResult[CheckedMotion]:
    """``motion line``: the ``request``'s hand in a straight line from ``pose`` with the whole body balancing,
    checked (:func:`check_motion`), the figure its path."""
    from op2motion.figures.paths import render_line
    from op2motion.formats.motionfile import motion_to_json
    from op2motion.motion.cartesian import line_move

    move: LineMove = line_move(pose, request, spec)
    motion = move.motion(name)
    trajectory = move.trajectory(motion.p_gain)
    summary, s = move.as_dict(spec), move.figures(spec)
    data = {"name": name, "pose": pose.name, "support": str(pose.support), **summary,
            "duration_s": round(trajectory.duration_s, 3), "ticks": len(trajectory.goals) - 1,
            "motion_file": how.motion_file}
    lines = [f"{name}: the {request.hand} hand from {pose.name}, {s.length_m * 1000:.1f} mm in "
             f"{trajectory.duration_s:.3f} s{' and back' if request.back else ''}: off the line <= "
             f"{s.line_deviation_max_m * 1000:.2f} mm, CoM margin >= {s.com_margin_min_m * 1000:.1f} "
             f"mm, fastest joint {s.joint_speed_joint} at {s.joint_speed_max_rad_s:.2f} rad/s; "
             f"solved {s.solved}" + (f" (the arm changes branch first, {s.reconfigure_s:.2f} s)"
                                     if s.reconfigure_s else "")]
    title = f"{name}: {request.hand} hand line from {pose.name}"
    text = motion_to_json(motion, spec, how.motion_file) if how.motion_file else None
    return check_motion(trajectory, spec, how, Told(title, data, lines),
                        lambda verdict: render_line(move, title, verdict), text, on_progress)
