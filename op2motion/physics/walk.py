"""A walk in physics: the gait's goals played every 8 ms into the servo model, judged and measured.

The robot starts at the plan's first torso pose (both soles flat on the floor), settles as gravity ramps in, walks,
and holds the last goal :data:`MOTION_HOLD_S`. The verdict is the motion verdict of :mod:`.run` against the
planned torso poses; a walk *fell* when the torso tilted, the CoM dropped or a link other than a foot touched the
floor. Measured on top:

* distance [m]: the whole-body CoM's horizontal travel from the first step to the end of the run; the mean speed
  is the steady walking speed: the CoM's travel over the ``steady`` window (from the second step's touchdown to
  the last advancing step's, so the start and the stop are left out) over its duration; the overall speed is the
  distance over the whole stepping time;
* lateral drift [m]: how far the CoM ended from its planned end, across the planned direction of travel (for a
  walk that does not travel, the whole distance); heading error [deg]: the torso's turn less the planned turn;
  turn rate [deg/s]: the torso's turn over the steady window;
* ``cop_inside_fraction``: share of the walk's samples whose measured centre of pressure lies inside the soles
  that should be on the floor at that moment (where they really are), by :data:`COP_TOLERANCE_M`;
* the largest servo torque of the walk against the servo's largest torque (at rest), and the share of samples
  in which some servo delivered :data:`LIMITED_FRACTION` of the torque available at its speed in the direction of
  that torque (at its limit; a braking servo has more, see :meth:`op2motion.model.servo.ServoModel.available`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.model.servo import ServoModel
from op2motion.physics.run import RAMP_S, Push
from op2motion.physics.scene import TIME_STEP_S
from op2motion.physics.schedule import Schedule
from op2motion.physics.verdict import Validation
from op2motion.robot.balance import convex_hull, polygon_margin
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

WALK_SETTLE_S = 0.5            # after gravity reached full strength, before the first goal moves
WALK_HOLD_S = 1.5              # the last goal held after the walk (the last second is the steady window)
FALL_REASONS = ("tilt", "com_drop", "ground_contact")
LIMITED_FRACTION = 0.95       # a servo delivering this share of the torque available at its speed is at its limit
COP_TOLERANCE_M = 0.001        # a measured CoP this close outside the soles still counts as inside (contact noise)
PUSH_SIDES = {"left": (0.0, 1.0), "right": (0.0, -1.0)}   # a push *from* the left pushes towards -Y, see _push


@dataclass(frozen=True)
class WalkRun:
    """One physics run of a walk: its verdict and the walking measurements (see the module docstring)."""

    validation: Validation
    fell: bool
    distance_m: float
    mean_speed_mps: float
    overall_speed_mps: float
    lateral_drift_m: float
    heading_error_deg: float
    turn_rate_deg_s: float
    cop_inside_fraction: float
    worst_torque: dict[str, Any]
    pushes: list[dict[str, Any]] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        """The JSON-ready measurements (the verdict's setup included)."""
        v = self.validation
        return {"engine": v.engine, "servo": v.servo, "time_step_s": v.time_step_s, "seconds": v.seconds,
                "fell": self.fell, "reasons": v.reasons, "distance_m": round(self.distance_m, 4),
                "mean_speed_mps": round(self.mean_speed_mps, 4),
                "overall_speed_mps": round(self.overall_speed_mps, 4),
                "lateral_drift_m": round(self.lateral_drift_m, 4),
                "heading_error_deg": round(self.heading_error_deg, 2),
                "turn_rate_deg_s": round(self.turn_rate_deg_s, 2),
                "cop_inside_fraction": round(self.cop_inside_fraction, 4), "worst_torque": self.worst_torque,
                "feet_slip_m": v.feet_slip_m, "self_collisions": v.self_collisions,
                "failures": [{"reason": f.reason, "time_s": round(f.time_s, 3), "detail": f.detail}
                             for f in v.failures],
                "pushes": self.pushes}


def _yaw(rot: np.ndarray) -> float:
    return math.atan2(float(rot[1, 0]), float(rot[0, 0]))


def _run(engine_name: str, schedule: Schedule, spec: Spec, servo: ServoModel, seconds: float, push: Push | None,
         offset: np.ndarray | None, on_step: Callable[[], Any] | None) -> tuple[Validation, Any, dict[str, Any]]:
    from op2motion.physics import judged_run

    return judged_run(engine_name, schedule, spec, servo, seconds, push, on_step, offset)


def validate_walk(goals: np.ndarray, p_gains: np.ndarray, supports: tuple[str, ...], contact: tuple[str, ...],
                  torso_pos: np.ndarray, torso_rot: np.ndarray, walking_s: float, steady: tuple[float, float],
                  spec: Spec,
                  dt: float = 0.008, engine: str = "pybullet", push_n: float = 0.0, push_at_s: float | None = None,
                  start_offset: np.ndarray | None = None, voltage: float | None = None,
                  start_joints: np.ndarray | None = None, on_step: Callable[[], Any] | None = None) -> WalkRun:
    """Play a walk: goals (K, 20) [rad] with P gains (K, 20) every ``dt`` [s], the physics support and the
    planned contact of every row, the planned torso poses (K, 3) [m] and (K, 3, 3), ``walking_s`` [s] of stepping
    (for the mean speed). ``push_n`` [N] pushes the torso for 0.1 s at ``push_at_s`` into the walk (default
    halfway) from the left and from the right, in separate runs; ``start_offset`` (20,) [rad] perturbs the start.
    ``start_joints`` (20,) [rad]: the planned joint angles of row 0 when the goals lead them (a servo feed-forward):
    the robot starts there and the goals move from them to row 0's as gravity ramps in."""
    if len(contact) != len(goals):
        raise InputError(f"expected one planned contact per row ({len(goals)}), got {len(contact)}", "walk")
    if not (math.isfinite(push_n) and 0.0 <= push_n <= 100.0):
        raise InputError(f"expected a push from 0 to 100 N, got {push_n!r}", "push")
    servo = ServoModel.of(spec, None, 1.0, voltage)
    start = RAMP_S + WALK_SETTLE_S
    lead = int(round(start / dt))
    first = np.asarray(goals[0], dtype=float)
    begin = first if start_joints is None else np.asarray(start_joints, dtype=float)
    ramp = np.minimum(1.0, np.arange(lead) * dt / RAMP_S)[:, None]
    rows = np.vstack([begin + ramp * (first - begin), goals])
    schedule = Schedule.motion(rows, np.vstack([np.repeat(p_gains[:1], lead, axis=0), p_gains]),
                               (supports[0],) * lead + tuple(supports), dt, 0.0, servo, spec).with_base(
        np.vstack([np.repeat(torso_pos[:1], lead, axis=0), torso_pos]),
        np.concatenate([np.repeat(torso_rot[:1], lead, axis=0), torso_rot]))
    contact = (contact[0],) * lead + tuple(contact)
    seconds = schedule.end_s + WALK_HOLD_S
    validation, track, facts = _run(engine, schedule, spec, servo, seconds, None, start_offset, on_step)
    run = _measure(validation, track, facts, schedule, contact, (start, walking_s, *steady), spec, servo.torque_max)
    if push_n > 0.0:
        at = start + (0.5 * (schedule.end_s - start) if push_at_s is None else push_at_s)
        pushes = []
        for side, (dx, dy) in PUSH_SIDES.items():
            push = Push(-np.array([dx, dy, 0.0]) * push_n, at, 0.1)
            pushed, _, _ = _run(engine, schedule, spec, servo, seconds, push, start_offset, None)
            pushes.append({"from": side, "force_n": push_n, "at_s": round(at - start, 3), "duration_s": 0.1,
                           "fell": bool(set(pushed.reasons) & set(FALL_REASONS)), "reasons": pushed.reasons})
        from dataclasses import replace

        run = replace(run, pushes=pushes)
    return run


def _measure(validation: Validation, track: Any, facts: dict[str, Any], schedule: Schedule,
             contact: tuple[str, ...], clock: tuple[float, float, float, float], spec: Spec,
             servo_max: float) -> WalkRun:
    start, walking_s, steady_from, steady_to = clock
    times = np.asarray(track.times)
    first = int(np.searchsorted(times, start))
    com = np.asarray(track.com)
    planned = facts["planned"].states
    start_c, end_c = com[first, :2], com[-1, :2]
    plan_start, plan_end = planned[0].com[:2], planned[-1].com[:2]
    travel = plan_end - plan_start
    distance = float(np.hypot(*(end_c - start_c)))
    error = end_c - (start_c + travel)
    if np.hypot(*travel) > 0.01:
        across = np.array([-travel[1], travel[0]]) / np.hypot(*travel)
        drift = abs(float(error @ across))
    else:
        drift = float(np.hypot(*error))
    yaw = np.unwrap([_yaw(r) for r in track.rot])                # turns of more than half a circle add up
    planned_yaw = np.unwrap([_yaw(r) for r in facts["planned"].rot])
    turned, planned_turn = float(yaw[-1] - yaw[first]), float(planned_yaw[-1] - planned_yaw[0])
    inside, counted = 0, 0
    for k in range(first, len(times)):
        if times[k] > schedule.end_s:
            break
        counted += 1
        cop = track.cop[k]
        if cop is None:
            continue
        state = track.states[k]
        hull = convex_hull(np.vstack([state.corners[s][:, :2] for s in Support.of(contact[track.rows[k]]).feet]))
        inside += polygon_margin(np.asarray(cop), hull)[0] >= -COP_TOLERANCE_M
    walking = (times >= start) & (times <= schedule.end_s)
    torque = np.abs(np.asarray(track.torque))[walking]
    k, j = np.unravel_index(int(np.argmax(torque)), torque.shape)
    limited = (torque >= LIMITED_FRACTION * np.asarray(track.available)[walking]).any(axis=1)
    worst = {"joint": spec.joint_names[j], "torque_nm": round(float(torque[k, j]), 4),
             "available_nm": round(servo_max, 4), "ratio": round(float(torque[k, j]) / servo_max, 4),
             "time_s": round(float(times[walking][k] - start), 3),
             "limited_share": round(float(limited.mean()), 4)}
    a, b = (int(min(np.searchsorted(times, start + t), len(times) - 1)) for t in (steady_from, steady_to))
    steady_s = max(float(times[b] - times[a]), 1e-9)
    steady_speed = float(np.hypot(*(com[b, :2] - com[a, :2]))) / steady_s
    return WalkRun(validation, bool(set(validation.reasons) & set(FALL_REASONS)), distance, steady_speed,
                   distance / max(walking_s, 1e-9), drift, math.degrees(turned - planned_turn),
                   math.degrees(float(yaw[b] - yaw[a])) / steady_s, inside / max(counted, 1), worst)


__all__ = ["FALL_REASONS", "TIME_STEP_S", "WALK_HOLD_S", "WALK_SETTLE_S", "WalkRun", "validate_walk"]
