"""The steered-walk task (``walk --commands``): a walk steered by a command timeline, planned as it would be while
walking (:class:`~op2motion.gait.steer.SteerableWalk`), optionally walked in physics (or over the robustness family,
judged as a commanded walk), drawn against the commanded path; a fall is a "no" with its phrase.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from op2motion.gait.steer import EndPose, PlannedWalk, SteerableWalk
from op2motion.jsonout import JsonObject, json_object
from op2motion.robot.spec import Spec
from op2motion.tasks.progress import ProgressFor, no_progress
from op2motion.tasks.result import Output, TaskResult
from op2motion.tasks.walk import walk_line

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import CommandTimeline
    from op2motion.physics import CheckReport, EngineName, RobustReport


@dataclass(frozen=True)
class SteeredRequest:
    """A commanded walk: the ``commands`` (a timeline), the kick pages of ``action`` (None: op2motion's own kicks),
    the step's ``preset`` (None: ``steer``); physics: ``validate``, ``robust`` (the family), in ``engines``, side
    pushes of ``push_n`` [N]; the ``plot`` PNG (the commanded, planned and walked paths)."""

    commands: CommandTimeline
    action: ActionFile | None = None
    preset: str | None = None
    validate: bool = False
    robust: bool = False
    engines: tuple[EngineName, ...] = ("pybullet",)
    push_n: float = 0.0
    plot: str | None = None


@dataclass(frozen=True)
class Commanded:
    """A command timeline in figures: its source, entries, length [s], events and where it ends."""

    source: str
    entries: int
    duration_s: float
    events: tuple[str, ...]
    end_pose: EndPose


def _commanded(timeline: CommandTimeline) -> Commanded:
    """``timeline`` in figures (see :class:`Commanded`)."""
    from op2motion.gait.commands import commanded_path

    _, poses = commanded_path(timeline)
    events = tuple(e.event for e in timeline.entries if e.event)
    return Commanded(timeline.source, len(timeline.entries), timeline.duration_s, events,
                     EndPose(float(poses[-1, 0]), float(poses[-1, 1]), math.degrees(float(poses[-1, 2]))))


def _physics(request: SteeredRequest, walk: Any, spec: Spec, data: dict[str, Any], progress: ProgressFor
             ) -> tuple[Any, str | None]:
    """The walk in physics (``robust``: over the family); the report and, for the family, its table."""
    from op2motion.gait import side_pushes, walk_summary
    from op2motion.gait.robust import commanded_judge, robust_table, walk_badness
    from op2motion.gait.steer import SteerableWalk
    from op2motion.physics import Setup, check, robust_check, robust_summary

    plan = walk.plan
    pushes = side_pushes(request.push_n) if request.push_n else None
    if request.robust:
        def fresh() -> Any:
            twin = SteerableWalk(walk.params, spec, walk.feedback, walk.envelope, walk.commands, walk.action)
            twin._plan = plan
            return twin

        with progress("robust", "run") as on_progress:
            family = robust_check(fresh, spec, request.engines, commanded_judge, pushes, on_progress=on_progress)
        data["robust"] = robust_summary(family)
        data["robust"]["worst"] = family.worst(walk_badness).member.name
        return family, robust_table(family)
    with progress("physics", "s") as on_progress:
        report = check(walk, spec, request.engines, pushes, setup=Setup(keep_track=bool(request.plot)),
                       on_progress=on_progress)
    data["physics"] = walk_summary(report, plan.walk.start_s if plan.walk else 0.0)
    data["fell"] = report.fell
    return report, None


def _figure(walk: Any, report: Any) -> bytes:
    """The commanded, planned and walked paths and headings."""
    import numpy as np

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


@dataclass(frozen=True)
class SteeredOutcome:
    """A commanded walk planned and checked: the ``commanded`` timeline and the ``planned`` walk in figures, the
    ``walk`` itself, its physics ``report`` (None: not walked, or walked over the family) and the robustness
    family's ``robust`` report (None: not asked)."""

    commanded: Commanded
    planned: PlannedWalk
    walk: SteerableWalk
    report: CheckReport | None
    robust: RobustReport | None


def steered_walk_task(request: SteeredRequest, spec: Spec, progress: ProgressFor | None = None
                      ) -> TaskResult[SteeredOutcome]:
    """``walk --commands``: see the module docstring; ``progress`` gives each stage's progress."""
    from op2motion.gait.steer import planned_summary

    progress = progress or no_progress
    walk = SteerableWalk.make(spec, request.preset, commands=request.commands, action=request.action)
    with progress("plan", "row"):
        summary = planned_summary(walk)
    commanded = _commanded(request.commands)
    data: JsonObject = {"preset": walk.params.name, "commands": json_object(commanded),
                        "planned": json_object(summary)}
    end = summary.end_pose
    timeline = request.commands
    lines = [f"walk --commands {timeline.source}: {len(timeline.entries)} entries over "
             f"{timeline.duration_s:g} s; planned {summary.steps} steps, {summary.kicks} kicks, "
             f"{summary.duration_s:.1f} s, ending at x {end.x_m:.3f} m, y {end.y_m:.3f} m, heading "
             f"{end.yaw_deg:+.1f}° (ZMP margin >= {summary.zmp_margin_min_m * 1000:.1f} mm)"]
    report, table = _physics(request, walk, spec, data, progress) if request.validate else (None, None)
    if table is not None:
        lines.append(table)
    elif report is not None:
        lines += [walk_line(r) for r in report.engines.values()]
    warnings = command_warnings(walk, request.commands, commanded.end_pose, summary)
    failed = report is not None and (not report.passed if table is not None else report.fell)
    outputs = {"plot": Output(request.plot, _figure(walk, report))} if request.plot else {}
    problem = f"the commanded walk {'failed in the robustness family' if table else 'fell in physics'}" if failed \
        else None
    outcome = SteeredOutcome(commanded, summary, walk, None if table is not None else report,
                             report if table is not None else None)
    return TaskResult(problem is None, problem, warnings, outputs, {**data, "files": {}}, tuple(lines), value=outcome)


END_M = 0.10                       # the plan may end this far from where the commands end without a warning [m]
END_DEG = 10.0                     # ... and turned this far from their heading [deg]


def command_warnings(walk: SteerableWalk, timeline: CommandTimeline, commanded_end: EndPose, planned: PlannedWalk
                     ) -> tuple[str, ...]:
    """What keeps the commands of ``timeline`` (``walk``'s) from being followed, in words: each command the
    envelope cuts (asked, and what it walks), each kick (the walk stops for it), where the plan ends against where
    the commands end (beyond :data:`END_M` or :data:`END_DEG`), and a planned ZMP outside the soles (when, during
    what)."""
    out = []
    for entry in timeline.entries:
        if entry.command is None:
            continue
        asked = entry.command
        kept = walk.envelope.clamp(*asked)
        if max(abs(a - k) for a, k in zip(asked, kept)) > 1e-9:
            out.append(f"{entry.t_s:g} s: the command ({_speeds(asked)}) is beyond the steered walk's envelope: it "
                       f"walks ({_speeds(kept)}) (docs/steering.md)")
    out += [f"{e.t_s:g} s: {e.event.replace('_', ' ')}: the walk stops, closes its feet and kicks, then walks on; the "
            f"commands meanwhile are not walked" for e in timeline.entries if e.event and e.event != "stop"]
    end = planned.end_pose
    off_m = math.hypot(end.x_m - commanded_end.x_m, end.y_m - commanded_end.y_m)
    off_deg = abs(math.remainder(end.yaw_deg - commanded_end.yaw_deg, 360.0))
    turned = abs(end.yaw_deg - commanded_end.yaw_deg)
    if off_m > END_M or turned > END_DEG:
        out.append(f"the plan ends at x {end.x_m:.3f} m, y {end.y_m:.3f} m, heading {end.yaw_deg:+.1f}°; "
                   f"the commands end at x {commanded_end.x_m:.3f} m, y {commanded_end.y_m:.3f} m, heading "
                   f"{commanded_end.yaw_deg:+.1f}° ({off_m:.2f} m and {min(off_deg, turned):.0f}° apart"
                   f"{', a turn of ' + format(turned, '.0f') + '° short' if turned > off_deg + 1e-6 else ''})")
    if planned.zmp_margin_min_m < 0.0:
        out.append(f"the planned ZMP leaves the soles by {-planned.zmp_margin_min_m * 1000:.1f} mm at "
                   f"{planned.zmp_margin_min_at_s:.2f} s (during a {planned.zmp_margin_min_during or 'phase'}): "
                   f"the plan itself would tip the robot there unless the servos' compliance and feedback catch it")
    return tuple(out)


def _speeds(command: tuple[float, float, float]) -> str:
    vx, vy, yaw_rate = command
    return f"{vx:+.3f} m/s forward, {vy:+.3f} m/s left, {math.degrees(yaw_rate):+.1f}°/s"
