"""A planned gait as people and other tools see it: the JSON summary, CSV and Webots exports, and the walk's
physics results (a :class:`~op2motion.physics.CheckReport` of its schedule, :mod:`.schedule`) as JSON.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np

from op2motion.errors import InputError
from op2motion.formats.tables import goals_csv, webots_rows
from op2motion.gait.generator import Gait
from op2motion.gait.measures import WalkMeasures
from op2motion.jsonout import JsonObject
from op2motion.physics import CheckReport, EngineReport, Pushes, RunReport
from op2motion.physics.report import OPPOSITE
from op2motion.robot.spec import Spec

STILL_M = 1e-3       # a plan that ends this close to where it started walks in place: its steady speed is 0 (the
#                      sway alone would show one over a short window)


def gait_summary(gait: Gait) -> JsonObject:
    """The plan's figures: steps, durations, distance and speed, ZMP margin, CoM height, footsteps, parameters."""
    end = gait.end_pose()
    distance = float(np.hypot(end[0], end[1]))
    worst = int(np.argmin(gait.zmp_margin))
    speed_window = gait.steady_window
    steady = gait.com[[int(round(t / gait.dt)) for t in speed_window], :2]
    return {
        "preset": gait.params.name, "steps": len(gait.footsteps.steps), "duration_s": round(gait.duration_s, 3),
        "walking_s": round(gait.walking_s, 3), "distance_m": round(distance, 4),
        "planned_speed_mps": 0.0 if distance < STILL_M else round(
            float(np.hypot(*(steady[1] - steady[0]))) / max(speed_window[1] - speed_window[0], 1e-9), 4),
        "end_pose": {"x_m": round(float(end[0]), 4), "y_m": round(float(end[1]), 4),
                     "yaw_deg": round(math.degrees(float(end[2])), 2)},
        "zmp_margin_min_m": round(float(gait.zmp_margin[worst]), 4),
        "zmp_margin_min_at_s": round(float(gait.times[worst]), 3),
        "com_height_m": round(gait.com_height, 4),
        "footsteps": [{"side": f.side, "x_m": round(f.x, 4), "y_m": round(f.y, 4),
                       "yaw_deg": round(math.degrees(f.yaw), 2)} for f in gait.footsteps.steps],
        "params": asdict(gait.params),
    }


def gait_csv(gait: Gait, spec: Spec) -> str:
    """The goals every 8 ms as CSV (time, support, degrees and ticks by joint name)."""
    return goals_csv(gait.times, gait.goals, gait.supports, spec)


def gait_webots(gait: Gait, spec: Spec) -> str:
    """The goals every 8 ms as a Webots ``.motion`` file (lines named by step: ``start``, ``step1``, ...)."""
    n = len(gait.footsteps.steps)
    names = ["start" if s < 0 else ("stop" if s >= n else f"step{s + 1}") for s in gait.timeline.step]
    return webots_rows(gait.times, gait.goals, spec, names)


def measured_walk(run: RunReport) -> WalkMeasures:
    """A walking run's walking measurements.

    Raises:
        InputError: ``run`` is not a walk's (its plan had no walking clock).
    """
    w = run.walk
    if not isinstance(w, WalkMeasures):
        raise InputError(f"expected the run of a walk (with walking measurements), got a {run.engine} run of a plan "
                         "without a walking clock", "report")
    return w


def _run_summary(run: RunReport) -> JsonObject:
    """One walking run's JSON: its setup, verdict and walking measurements."""
    w = measured_walk(run)
    return {"engine": run.engine, "servo": run.servo, "time_step_s": run.time_step_s, "seconds": run.seconds,
            "fell": run.fell, "reasons": run.reasons, "distance_m": round(w.distance_m, 4),
            "mean_speed_mps": round(w.mean_speed_mps, 4), "overall_speed_mps": round(w.overall_speed_mps, 4),
            "lateral_drift_m": round(w.lateral_drift_m, 4), "heading_error_deg": round(w.heading_error_deg, 2),
            "turn_rate_deg_s": round(w.turn_rate_deg_s, 2), "cop_inside_fraction": round(w.cop_inside_fraction, 4),
            "worst_torque": w.worst_torque.as_dict(), "feet_slip_m": run.feet_slip_m,
            "self_collisions": [list(p) for p in run.self_collisions],
            "failures": [{"reason": f.reason, "time_s": round(f.time_s, 3), "detail": f.detail} for f in run.failures]}


def engine_summary(report: EngineReport, walk_start_s: float) -> JsonObject:
    """One engine's walk JSON: the main run, the side pushes (``from`` the side the push comes from, ``at_s`` [s]
    into the walk) and the perturbed trials."""
    out = _run_summary(report.run)
    out["pushes"] = [{"from": OPPOSITE[p.direction], "force_n": p.force_n, "at_s": round(p.start_s - walk_start_s, 3),
                      "duration_s": p.duration_s, "fell": p.fell, "reasons": p.reasons} for p in report.pushes]
    if report.trials is not None:
        runs = report.trials.runs
        out["trials"] = {"runs": len(runs), "walked": report.trials.survived, "perturb_deg": report.trials.perturb_deg,
                         "seed": report.trials.seed,
                         "mean_speed_mps": [round(r.walk.mean_speed_mps, 4) if r.walk else 0.0 for r in runs],
                         "reasons": [r.reasons for r in runs]}
    return out


def walk_summary(report: CheckReport, walk_start_s: float) -> JsonObject:
    """The walk's physics JSON: each engine's summary, ``fell`` (any engine's main run), ``agree`` and whether
    every push was survived."""
    return {"engines": {name: engine_summary(e, walk_start_s) for name, e in report.engines.items()},
            "fell": report.fell, "agree": report.agree, "pushes_survived": report.pushes_survived}


def side_pushes(force_n: float) -> Pushes:
    """A walk's pushes: ``force_n`` [N] from the left, then from the right (the force pointing right, then left),
    halfway through the walk."""
    return Pushes(force_n, ("right", "left"))
