"""The numbers behind a verdict: margins, tilts, torques, sag, the feet's loads, a motion's tracking.

:func:`run_report` assembles a :class:`.report.RunReport` from a recorded run, its judged failures and its setup. The
margins are to the real support polygon (the sole boxes, :meth:`op2motion.robot.support.Support.polygon`); the
torques and sag are means over the steady window (the last second); a motion adds its tracking error and worst
torque while it plays (:func:`motion_measures`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from op2motion.model.servo import ServoModel
from op2motion.physics.body import margin_to
from op2motion.physics.judge import LOADING_TILT_LIMIT_DEG, Judgement, steady_window
from op2motion.physics.loop import StartFacts
from op2motion.physics.plan import Plan
from op2motion.physics.report import FootLoad, MotionMeasures, RunReport, WorstTorque
from op2motion.physics.scene import EngineName
from op2motion.physics.track import Track
from op2motion.robot.balance import polygon_margin
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

PLAYING_AFTER_S = 0.5       # a motion's tracking is measured until this long after its last goal


@dataclass(frozen=True)
class RunSetupFacts:
    """What a report says about its run's setup: engine, servo model, time step [s]."""

    engine: EngineName
    servo: ServoModel
    time_step_s: float


def _r(v: float, digits: int = 5) -> float:
    return round(float(v), digits)


def _xy(v: Sequence[float] | np.ndarray) -> tuple[float, float]:
    return _r(v[0]), _r(v[1])


def _xyz(v: Sequence[float] | np.ndarray) -> tuple[float, float, float]:
    return _r(v[0]), _r(v[1]), _r(v[2])


def feet_report(track: Track, steady: np.ndarray) -> dict[str, FootLoad]:
    """Each foot's share of the load and its own centre of pressure over the steady window, with the CoP's margin
    to that foot's sole [m] (a foot tips when its own CoP reaches its edge, whatever the other foot carries)."""
    out = {}
    samples = [f for f, s in zip(track.feet, steady) if s]
    total = sum(sum(w for w, _ in f.values()) for f in samples)
    last = track.states[-1]
    for side in ("left", "right"):
        weights = np.array([f[side][0] for f in samples if side in f])
        if total <= 0.0 or weights.sum() <= 0.0:
            continue
        cop = sum(f[side][0] * f[side][1] for f in samples if side in f) / weights.sum()
        margin = float(polygon_margin(cop, Support.of(side).polygon(last.corners))[0])
        out[side] = FootLoad(_r(weights.sum() / total, 4), _xy(cop), _r(margin))
    return out


def motion_measures(track: Track, plan: Plan, spec: Spec) -> MotionMeasures | None:
    """A motion's tracking error per joint (goal - measured) while it plays and :data:`PLAYING_AFTER_S` after,
    the worst torque against what was available then, and the centre-of-pressure track; None for a held pose."""
    if not plan.is_motion:
        return None
    times = track.times
    playing = (times >= plan.start_s) & (times <= plan.end_s + PLAYING_AFTER_S)
    error = np.degrees(np.abs(track.goals[playing] - track.q[playing]))
    torque, available = np.abs(track.torque[playing]), track.available[playing]
    k, j = np.unravel_index(int(np.argmax(torque / np.maximum(available, 1e-9))), torque.shape)
    names = spec.joint_names
    return MotionMeasures(
        {n: _r(v, 3) for n, v in zip(names, error.max(axis=0))},
        {n: _r(v, 3) for n, v in zip(names, np.sqrt((error ** 2).mean(axis=0)))},
        WorstTorque(names[j], _r(torque[k, j], 4), _r(available[k, j], 4), _r(times[playing][k], 3)),
        tuple((_r(t, 3), _r(c[0]), _r(c[1])) for t, c in zip(times, track.cop) if c is not None))


def _torques(track: Track, steady: np.ndarray, spec: Spec) -> dict[str, Any]:
    torque, available = np.abs(track.torque), track.available
    mean = torque[steady].mean(axis=0)
    worst = int(np.argmax(mean / np.maximum(available[steady].mean(axis=0), 1e-9)))
    return {"max_torque_nm": _r(mean[worst], 4),
            "torque_ratio": _r(mean[worst] / max(available[steady][:, worst].mean(), 1e-9), 4),
            "worst_joint": spec.joint_names[worst], "peak_torque_nm": _r(torque.max(), 4),
            "sag_deg": {n: _r(math.degrees(v), 3)
                        for n, v in zip(spec.joint_names, (track.q[steady] - track.goals[steady]).mean(axis=0))}}


def _tilts(from_start: np.ndarray, tilt: np.ndarray, loaded: int, fell_loading: bool) -> dict[str, Any]:
    return {"max_tilt_deg": _r(tilt.max() if not fell_loading else from_start.max(), 3),
            "settled_tilt_deg": _r(from_start[-1], 3), "load_tilt_deg": _r(from_start[loaded], 3)}


def run_report(track: Track, start: StartFacts, plan: Plan, spec: Spec, judged: Judgement,
               setup: RunSetupFacts) -> RunReport:
    """The report of a judged run (see the module docstring)."""
    steady = steady_window(track.times)
    fell_loading = bool(np.any(judged.from_start_deg[:judged.loaded] > LOADING_TILT_LIMIT_DEG))
    last, load_state = track.states[-1], track.states[judged.loaded]
    final = plan.supports[-1]
    cops = [c for c, s in zip(track.cop, steady) if s and c is not None]
    com = track.com
    return RunReport(
        engine=setup.engine, servo=setup.servo.describe(), time_step_s=setup.time_step_s,
        seconds=round(float(track.times[-1]), 3), planned_seconds=plan.duration_s, ended=start.ended,
        failures=judged.failures, support_margin_m=_r(margin_to(last, final, com[-1, :2])),
        margin_at_load_m=_r(margin_to(load_state, plan.supports[0], load_state.com[:2])),
        cop_xy=None if not cops else _xy(np.mean(cops, axis=0)),
        com_settled=_xyz(com[-1]), com_start=_xyz(start.state.com),
        **_tilts(judged.from_start_deg, judged.tilt_deg, judged.loaded, fell_loading),
        com_drift_m=_r(np.max(np.hypot(*(com[:, :2] - start.state.com[:2]).T))),
        feet_slip_m=_r(judged.slip_m), start_gap_m=_r(start.planned.gap), flat_foot=start.planned.flat_foot,
        self_collisions=tuple(sorted({p for pairs in track.self_pairs for p in pairs})),
        ground_contacts=tuple(sorted({link for g in track.ground for link in g})),
        **_torques(track, steady, spec),
        swing_foot_min_z_m=None if final.swing is None else _r(last.corners[final.swing][:, 2].min()),
        feet=feet_report(track, steady), motion=motion_measures(track, plan, spec))
