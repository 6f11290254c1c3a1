"""A planned gait as people and other tools see it: the JSON summary, CSV and Webots exports, physics runs.

:func:`walk_physics` plays the gait in each engine asked for (:func:`op2motion.physics.walk.validate_walk`), with
optional side pushes and repeated runs from randomly perturbed starts (seeded), and says whether the engines agree.
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any, Callable, Sequence

import numpy as np

from op2motion.formats.tables import goals_csv, webots_rows
from op2motion.gait.generator import Gait
from op2motion.physics.walk import validate_walk
from op2motion.robot.spec import Spec


def gait_summary(gait: Gait) -> dict[str, Any]:
    """The plan's figures: steps, durations, distance and speed, ZMP margin, CoM height, footsteps, parameters."""
    end = gait.end_pose()
    distance = float(np.hypot(end[0], end[1]))
    worst = int(np.argmin(gait.zmp_margin))
    speed_window = gait.steady_window
    steady = gait.com[[int(round(t / gait.dt)) for t in speed_window], :2]
    return {
        "preset": gait.params.name, "steps": len(gait.plan.steps), "duration_s": round(gait.duration_s, 3),
        "walking_s": round(gait.walking_s, 3), "distance_m": round(distance, 4),
        "planned_speed_mps": round(float(np.hypot(*(steady[1] - steady[0]))) /
                                   max(speed_window[1] - speed_window[0], 1e-9), 4),
        "end_pose": {"x_m": round(float(end[0]), 4), "y_m": round(float(end[1]), 4),
                     "yaw_deg": round(math.degrees(float(end[2])), 2)},
        "zmp_margin_min_m": round(float(gait.zmp_margin[worst]), 4),
        "zmp_margin_min_at_s": round(float(gait.times[worst]), 3),
        "com_height_m": round(gait.com_height, 4),
        "footsteps": [{"side": f.side, "x_m": round(f.x, 4), "y_m": round(f.y, 4),
                       "yaw_deg": round(math.degrees(f.yaw), 2)} for f in gait.plan.steps],
        "params": asdict(gait.params),
    }


def gait_csv(gait: Gait, spec: Spec) -> str:
    """The goals every 8 ms as CSV (time, support, degrees and ticks by joint name)."""
    return goals_csv(gait.times, gait.goals, gait.supports, spec)


def gait_webots(gait: Gait, spec: Spec) -> str:
    """The goals every 8 ms as a Webots ``.motion`` file (lines named by step: ``start``, ``step1``, ...)."""
    n = len(gait.plan.steps)
    names = ["start" if s < 0 else ("stop" if s >= n else f"step{s + 1}") for s in gait.timeline.step]
    return webots_rows(gait.times, gait.goals, spec, names)


def walk_physics(gait: Gait, spec: Spec, engines: Sequence[str], push_n: float = 0.0, trials: int = 0,
                 perturb_deg: float = 0.5, seed: int = 0,
                 on_step: Callable[[], Any] | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """Play ``gait`` in each engine: the walk's measurements, side pushes of ``push_n`` [N], and ``trials`` more
    runs each starting with every joint off its first goal by a normal draw of ``perturb_deg`` [deg] (seed
    ``seed``). Returns the JSON-ready results with ``fell`` (any engine's main run), ``agree`` and the trials'
    counts, and each engine's main run (:class:`op2motion.physics.walk.WalkRun`)."""
    out: dict[str, Any] = {"engines": {}}
    runs: dict[str, Any] = {}
    rng = np.random.default_rng(seed)
    offsets = [np.radians(rng.normal(0.0, perturb_deg, len(spec.joints))) for _ in range(trials)]

    def run(engine: str, push: float, offset: np.ndarray | None) -> Any:
        return validate_walk(gait.goals, gait.p_gains, gait.supports, gait.timeline.contact, gait.torso_pos,
                             gait.torso_rot, gait.walking_s, gait.steady_window, spec, gait.dt, engine, push,
                             start_offset=offset, start_joints=gait.joints[0], on_step=on_step)

    for engine in engines:
        runs[engine] = run(engine, push_n, None)
        summary = runs[engine].summary()
        if trials:
            results = [run(engine, 0.0, o) for o in offsets]
            summary["trials"] = {"runs": trials, "walked": sum(not r.fell for r in results),
                                 "perturb_deg": perturb_deg, "seed": seed,
                                 "mean_speed_mps": [round(r.mean_speed_mps, 4) for r in results],
                                 "reasons": [r.validation.reasons for r in results]}
        out["engines"][engine] = summary
    verdicts = [s["fell"] for s in out["engines"].values()]
    out["fell"] = any(verdicts)
    out["agree"] = len(set(verdicts)) == 1
    out["pushes_survived"] = all(not p["fell"] for s in out["engines"].values() for p in s["pushes"])
    return out, runs
