"""A walk across what we do not know: the robustness family (:mod:`op2motion.physics.robust`) with a walk's judge.

A walk passes in one member and engine when it does not fall (nor when pushed), its lateral drift is at most
:data:`MAX_DRIFT_SHARE` of the distance walked and its heading error at most :data:`MAX_HEADING_DEG` (a turn's
heading error is against its planned turn). :func:`robust_table` prints the family's runs as
Markdown (the JSON: :func:`op2motion.physics.robust_table.robust_summary`).
"""

from __future__ import annotations

from op2motion.gait.measures import WalkMeasures
from op2motion.physics import EngineReport, RobustReport, RobustRun, robust_markdown

MAX_DRIFT_SHARE = 0.05      # lateral drift over distance walked
MAX_HEADING_DEG = 5.0       # heading error at the end [deg]
MIN_DISTANCE_M = 0.5        # drift is judged against at least this distance: a turn in place may wander 25 mm


def _measured(report: EngineReport) -> tuple[WalkMeasures | None, str | None]:
    """The walk's measures, or None and why there are none to judge (a fall, a fall when pushed, none measured)."""
    run = report.run
    if run.fell:
        return None, run.reason
    fallen = [p.direction for p in report.pushes if p.fell]
    if fallen:
        return None, f"fell when pushed {', '.join(fallen)}"
    if run.walk is None:
        return None, "no walk measured"
    return run.walk, None


def walk_judge(report: EngineReport) -> str | None:
    """None when the walk passed; else why not, in one phrase."""
    walk, why = _measured(report)
    if walk is None:
        return why
    distance = max(walk.distance_m, MIN_DISTANCE_M)
    if walk.lateral_drift_m > MAX_DRIFT_SHARE * distance:
        return f"drifted {walk.lateral_drift_m * 1000:.0f} mm ({walk.lateral_drift_m / distance:.0%} of the distance)"
    if abs(walk.heading_error_deg) > MAX_HEADING_DEG:
        return f"heading off by {walk.heading_error_deg:+.1f}°"
    return None


def walk_badness(run: RobustRun) -> float:
    """How badly a walk went, for picking the worst case: falls first, then drift share and heading."""
    walk = run.report.run.walk
    if run.report.run.fell or walk is None:
        return 1e6
    distance = max(walk.distance_m, MIN_DISTANCE_M)
    badness: float = max(walk.lateral_drift_m / distance / MAX_DRIFT_SHARE,
                         abs(walk.heading_error_deg) / MAX_HEADING_DEG, -walk.mean_speed_mps)
    return badness


def _walk_cells(run: RobustRun) -> list[str]:
    walk, rep = run.report.run.walk, run.report
    pushes = f"{sum(not p.fell for p in rep.pushes)}/{len(rep.pushes)}" if rep.pushes else "–"
    if walk is None:
        return ["–", "–", "–", pushes]
    return [f"{walk.mean_speed_mps:.3f}", f"{walk.lateral_drift_m * 1000:.0f} mm "
            f"({walk.lateral_drift_m / max(walk.distance_m, MIN_DISTANCE_M):.1%})", f"{walk.heading_error_deg:+.1f}°",
            pushes]


def robust_table(report: RobustReport) -> str:
    """A walk's family as Markdown: speed, drift, heading, pushes, verdict per run; the summary line."""
    head = ["steady speed [m/s]", "drift", "heading", "pushes survived"]
    return robust_markdown(report, head, _walk_cells, walk_badness)


MAX_COMMANDED_HEADING_DEG = 15.0    # a commanded walk ends within this of its planned heading [deg]
MAX_COMMANDED_DRIFT_SHARE = 0.15    # ... and this share of its distance off the planned end across the way it went
MIN_COMMANDED_DRIFT_M = 0.1         # ... (at least this much: a commanded walk turns and side-steps)


def commanded_judge(report: EngineReport) -> str | None:
    """A commanded walk's judge (``walk --commands``): no fall (nor when pushed), the heading within
    :data:`MAX_COMMANDED_HEADING_DEG` of the plan's and the end within :data:`MAX_COMMANDED_DRIFT_SHARE` of the
    distance of the planned end across the way it went (dead reckoning over turns and side steps adds up: looser than
    a straight walk's :func:`walk_judge`); None when it passed."""
    walk, why = _measured(report)
    if walk is None:
        return why
    allowed = max(MIN_COMMANDED_DRIFT_M, MAX_COMMANDED_DRIFT_SHARE * walk.distance_m)
    if walk.lateral_drift_m > allowed:
        return f"drifted {walk.lateral_drift_m * 1000:.0f} mm (allowed {allowed * 1000:.0f} mm)"
    if abs(walk.heading_error_deg) > MAX_COMMANDED_HEADING_DEG:
        return f"heading off by {walk.heading_error_deg:+.1f}°"
    return None
