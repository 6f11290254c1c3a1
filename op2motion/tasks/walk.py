"""The walk task: a ZMP preview-control walk planned from a gait preset (within the servos' speed, or re-timed),
optionally walked in physics under :class:`~op2motion.gait.controller.WalkController` (or open loop), pushed, from
perturbed starts, or over the robustness family; its figure and goal tables as outputs. A walk that falls, falls when
pushed, or fails a member of the family is a "no" with its phrase (nothing to write), not an exception.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from op2motion.jsonout import JsonObject
from op2motion.robot.spec import Spec
from op2motion.tasks.progress import ProgressFor, no_progress
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.gait.generator import Gait
    from op2motion.gait.params import GaitParams
    from op2motion.physics import CheckReport, EngineName, EngineReport, RobustReport, Trials

#: The goal tables a walk writes, by file ending.
OUT_FORMATS = {".csv": "csv", ".motion": "webots"}


@dataclass(frozen=True)
class WalkRequest:
    """A walk to plan and check: the preset's ``params``, a ``target`` pose (x [m], y [m], heading [rad]) to walk
    to instead of its steps (None: its steps), ``retime`` (lengthen the step instead of refusing a joint too fast);
    physics: ``validate``, ``open_loop`` (the planned goals without feedback), ``robust`` (the family), in
    ``engines``, side pushes of ``push_n`` [N], perturbed starts (``trials``); outputs: the ``plot`` PNG and the
    goal tables ``tables`` ({role: path}, each ending in .csv or .motion)."""

    params: GaitParams
    target: tuple[float, float, float] | None = None
    retime: bool = False
    validate: bool = False
    open_loop: bool = False
    robust: bool = False
    engines: tuple[EngineName, ...] = ("pybullet",)
    push_n: float = 0.0
    trials: Trials | None = None
    plot: str | None = None
    tables: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class WalkOutcome:
    """A walk planned and checked: the ``gait`` (its plan), its physics ``report`` (None: not walked in physics, or
    walked over the family) and the robustness family's report ``robust`` (None: not asked)."""

    gait: Gait
    report: CheckReport | None
    robust: RobustReport | None


def walk_line(report: EngineReport) -> str:
    """One engine's walk in words (``report``: the engine's check of a walk, with its walking measurements)."""
    from op2motion.gait.report import measured_walk
    from op2motion.physics.report import OPPOSITE

    run = report.run
    s = measured_walk(run)
    w = s.worst_torque
    line = (f"  {run.engine}: {'FELL' if run.fell else 'walked'}"
            f"{' (' + ', '.join(run.reasons) + ')' if run.reasons else ''}, {s.distance_m:.3f} m, "
            f"{s.mean_speed_mps:.3f} m/s steady, drift {s.lateral_drift_m * 1000:.0f} mm, heading off "
            f"the plan's by {s.heading_error_deg:+.1f}°, turn {s.turn_rate_deg_s:.1f}°/s, CoP inside "
            f"{s.cop_inside_fraction:.1%}, worst torque {w.torque_nm:.2f} N·m at {w.joint} "
            f"({w.ratio:.0%} of {w.available_nm:.2f})")
    if report.pushes:
        line += "; pushes: " + ", ".join(f"from {OPPOSITE[p.direction]} {'FELL' if p.fell else 'ok'}"
                                         for p in report.pushes)
    if report.trials is not None:
        line += f"; trials: {report.trials.survived}/{len(report.trials.runs)} walked"
    return line


def _controller(request: WalkRequest, gait: Any, spec: Spec) -> Any:
    """The walk's controller: the closed loop, or open loop the planned goals as they are."""
    from op2motion.gait import gait_schedule
    from op2motion.gait.controller import WalkController

    return gait_schedule(gait, spec) if request.open_loop else WalkController(gait, spec)


def _physics(request: WalkRequest, gait: Any, spec: Spec, data: JsonObject, progress: ProgressFor
             ) -> CheckReport:
    """The walk in physics; its figures go into ``data``."""
    from op2motion.gait import side_pushes, walk_summary
    from op2motion.gait.report import measured_walk
    from op2motion.physics import check

    controller = _controller(request, gait, spec)
    with progress("physics", "s") as on_progress:
        report = check(controller, spec, request.engines, side_pushes(request.push_n) if request.push_n else None,
                       request.trials, on_progress=on_progress)
    main = measured_walk(report.run)
    data["physics"] = walk_summary(report, controller.plan.walk.start_s if controller.plan.walk else 0.0)
    data["controller"] = "open loop" if request.open_loop else "WalkController"
    data.update(reasons=list(report.run.reasons), lateral_drift_m=main.lateral_drift_m,
                heading_error_deg=main.heading_error_deg, turn_rate_deg_s=main.turn_rate_deg_s,
                cop_inside_fraction=main.cop_inside_fraction, worst_torque=main.worst_torque.as_dict(),
                mean_speed_mps=min(measured_walk(e.run).mean_speed_mps for e in report.engines.values()),
                fell=report.fell)
    return report


def _robust(request: WalkRequest, gait: Any, spec: Spec, data: JsonObject, progress: ProgressFor
            ) -> tuple[RobustReport, str]:
    """The walk over the robustness family; its summary goes into ``data``; the report and its table."""
    from op2motion.gait import side_pushes
    from op2motion.gait.robust import robust_table, walk_badness, walk_judge
    from op2motion.physics import robust_check, robust_summary

    with progress("robust", "run") as on_progress:
        report = robust_check(lambda: _controller(request, gait, spec), spec, request.engines, walk_judge,
                              side_pushes(request.push_n) if request.push_n else None, on_progress=on_progress)
    data["robust"] = {**robust_summary(report), "worst": report.worst(walk_badness).member.name}
    return report, robust_table(report)


def _outputs(request: WalkRequest, gait: Any, spec: Spec, report: CheckReport | None) -> dict[str, Output]:
    """The plot and the goal tables asked for."""
    from pathlib import Path

    from op2motion.figures.gait import render_gait
    from op2motion.gait import gait_csv, gait_webots
    from op2motion.gait.measures import WALK_SETTLE_S
    from op2motion.physics import RAMP_S

    out: dict[str, Output] = {}
    for role, path in request.tables:
        fmt = OUT_FORMATS[Path(path).suffix.lower()]
        out[role] = Output(path, gait_csv(gait, spec) if fmt == "csv" else gait_webots(gait, spec))
    if request.plot:
        verdict = "not checked in physics" if report is None else " | ".join(
            f"{e}: {'fell' if r.run.fell else 'walked'} {r.run.walk.mean_speed_mps if r.run.walk else 0.0:.3f} "
            f"m/s" for e, r in report.engines.items())
        cop = report.run.motion.cop_track if report is not None and report.run.motion else None
        out["plot"] = Output(request.plot, render_gait(gait, spec, f"walk '{gait.params.name}'", cop,
                                                       RAMP_S + WALK_SETTLE_S, verdict))
    return out


def _problem(name: str, robust: Any, report: CheckReport | None) -> str | None:
    """Why the walk's check says no (None: it does not)."""
    if robust is not None and not robust.passed:
        return (f"walk '{name}' failed in {sum(not r.passed for r in robust.runs)} of {len(robust.runs)} runs of "
                f"the robustness family")
    if report is not None and report.fell:
        return f"walk '{name}' fell in physics: " + "; ".join(
            f"{e}: {', '.join(r.run.reasons)}" for e, r in report.engines.items() if r.run.fell)
    if report is not None and not report.pushes_survived:
        return f"walk '{name}' " + (report.problem("does not get through", fall_only=True) or "fell when pushed")
    return None


def _refuse_work_early(request: WalkRequest, spec: Spec) -> None:
    """Refuse, before planning, a check that would simulate more than the cap even for the shortest walk of its
    steps (the walk lasts at least ``steps`` x ``step_s``; the check after planning counts its whole duration)."""
    from op2motion.gait import side_pushes
    from op2motion.physics import check_runs, check_work, family, robust_runs

    pushes = side_pushes(request.push_n) if request.push_n else None
    engines = len(request.engines)
    runs = (robust_runs(len(family(spec)), engines, pushes) if request.robust
            else check_runs(engines, pushes, request.trials))
    check_work(runs, request.params.steps * request.params.step_s)


def walk_task(request: WalkRequest, spec: Spec, progress: ProgressFor | None = None) -> TaskResult[WalkOutcome]:
    """``walk``: plan ``request``'s walk and check it (see the module docstring); ``progress`` gives each stage's
    progress (the plan's passes, the physics' simulated seconds, the family's runs)."""
    from op2motion.gait import gait_summary
    from op2motion.gait.speeds import gait_within_speed

    progress = progress or no_progress
    params = request.params
    if request.validate and request.target is None:
        _refuse_work_early(request, spec)
    with progress("plan", "pass") as on_progress:
        gait = gait_within_speed(params, spec, request.target, request.retime, on_progress)
    data: dict[str, Any] = gait_summary(gait)
    lines = [f"walk '{params.name}': {data['steps']} steps in {data['walking_s']:.2f} s, "
             f"{data['distance_m']:.3f} m planned ({data['planned_speed_mps']:.3f} m/s steady), ZMP margin >= "
             f"{data['zmp_margin_min_m'] * 1000:.1f} mm, CoM height {data['com_height_m']:.3f} m"]
    if gait.params.step_s != params.step_s:
        lines.append(f"  re-timed: step {params.step_s:.3f} s -> {gait.params.step_s:.3f} s (joint speeds)")
    data["step_s"] = gait.params.step_s
    robust = _robust(request, gait, spec, data, progress) if request.validate and request.robust else None
    report = _physics(request, gait, spec, data, progress) if request.validate and robust is None else None
    if report is not None:
        lines += [walk_line(r) for r in report.engines.values()]
    if robust is not None:
        lines.append(robust[1])
    problem = _problem(params.name, None if robust is None else robust[0], report)
    outputs = _outputs(request, gait, spec, report)
    outcome = WalkOutcome(gait, report, None if robust is None else robust[0])
    return TaskResult(problem is None, problem, None, outputs, {**data, "files": {}}, tuple(lines), value=outcome)
