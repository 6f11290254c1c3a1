"""A walk's measurements, from a recorded run and its plan's walking clock (:class:`~op2motion.physics.WalkClock`).

Every walk plan the gait builds carries :func:`walk_measures` as its hook (:attr:`op2motion.physics.Plan.measure`):
the physics check calls it after each run and stores the :class:`WalkMeasures` in the run report's ``walk`` slot
(:attr:`op2motion.physics.RunReport.walk`); physics itself knows nothing of walks.

* distance [m]: the whole-body CoM's horizontal travel from the first step to the end of the run; the mean speed
  is the steady walking speed: the CoM's travel over the steady window (from the second step's touchdown to the
  last advancing step's, so the start and the stop are left out) over its duration; the overall speed is the
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
from dataclasses import dataclass

import numpy as np

from op2motion.errors import InputError
from op2motion.jsonout import JsonObject
from op2motion.physics import Plan, StartFacts, Track, WalkClock, WorstTorque, margin_to
from op2motion.robot.spec import Spec

WALK_SETTLE_S = 0.5            # after gravity reached full strength, before the first goal moves
WALK_HOLD_S = 1.5              # the last goal held after the walk (the last second is the steady window)
LIMITED_FRACTION = 0.95        # a servo delivering this share of the torque available at its speed is at its limit
COP_TOLERANCE_M = 0.001        # a measured CoP this close outside the soles still counts as inside (contact noise)


@dataclass(frozen=True)
class WalkMeasures:
    """A walk's measurements (see the module docstring): distance [m], steady and overall speed [m/s], lateral drift
    [m], heading error [deg], turn rate [deg/s], share of samples with the CoP inside the planned soles, worst
    torque."""

    distance_m: float
    mean_speed_mps: float
    overall_speed_mps: float
    lateral_drift_m: float
    heading_error_deg: float
    turn_rate_deg_s: float
    cop_inside_fraction: float
    worst_torque: WorstTorque

    def robust_row(self) -> JsonObject:
        """The walk's columns in the robustness family's JSON (:func:`op2motion.physics.robust_summary`): steady
        speed [m/s], lateral drift [m], heading error [deg], distance [m], rounded."""
        return {"mean_speed_mps": round(self.mean_speed_mps, 4), "lateral_drift_m": round(self.lateral_drift_m, 4),
                "heading_error_deg": round(self.heading_error_deg, 2), "distance_m": round(self.distance_m, 4)}


def _yaw(rot: np.ndarray) -> float:
    return math.atan2(float(rot[1, 0]), float(rot[0, 0]))


def _drift(end: np.ndarray, start: np.ndarray, travel: np.ndarray) -> float:
    """How far ``end`` (2,) lies from ``start`` + ``travel`` across the direction of travel [m] (all of it for a
    walk that does not travel)."""
    error = end - (start + travel)
    if np.hypot(*travel) <= 0.01:
        return float(np.hypot(*error))
    across = np.array([-travel[1], travel[0]]) / np.hypot(*travel)
    return abs(float(error @ across))


def cop_inside_fraction(track: Track, plan: Plan, first: int) -> float:
    """Share of the samples from ``first`` to the end of the plan's motion whose CoP lies inside the soles of the
    planned contact (where they are)."""
    inside, counted = 0, 0
    for k in range(first, len(track.times)):
        if track.times[k] > plan.end_s:
            break
        counted += 1
        cop = track.cop[k]
        if cop is not None:
            inside += margin_to(track.states[k], plan.contacts[track.rows[k]], cop) >= -COP_TOLERANCE_M
    return inside / max(counted, 1)


def worst_walk_torque(track: Track, plan: Plan, spec: Spec, clock: WalkClock) -> WorstTorque:
    """The servo torque nearest its limit while walking, against what that servo could deliver at that moment (its
    speed and the torque's direction: a braking servo has more than its stall torque, so a torque over 2.41 N·m is
    not an overload), and the share of samples with some servo at its limit."""
    times = track.times
    walking = (times >= clock.start_s) & (times <= plan.end_s)
    torque, available = np.abs(track.torque)[walking], track.available[walking]
    share = torque / np.maximum(available, 1e-9)
    k, j = np.unravel_index(int(np.argmax(share)), share.shape)
    limited = (torque >= LIMITED_FRACTION * available).any(axis=1)
    return WorstTorque(spec.joint_names[j], round(float(torque[k, j]), 4), round(float(available[k, j]), 4),
                       round(float(times[walking][k] - clock.start_s), 3), round(float(limited.mean()), 4))


def walk_measures(track: Track, start: StartFacts, plan: Plan, spec: Spec) -> WalkMeasures:
    """The measurements of a walk (see the module docstring); the hook of every walk plan
    (:attr:`op2motion.physics.Plan.measure`)."""
    clock = plan.walk
    if clock is None:
        raise InputError(f"expected a walk's plan (with a walking clock), got a '{plan.kind}' plan", "plan")
    times, com = track.times, track.com
    first = int(np.searchsorted(times, clock.start_s))
    planned = start.planned
    travel = planned.states[-1].com[:2] - planned.states[0].com[:2]
    distance = float(np.hypot(*(com[-1, :2] - com[first, :2])))
    yaw = np.unwrap([_yaw(r) for r in track.rot])                # turns of more than half a circle add up
    planned_yaw = np.unwrap([_yaw(r) for r in planned.rot])
    a, b = (min(int(np.searchsorted(times, clock.start_s + t)), len(times) - 1)
            for t in (clock.steady_from_s, clock.steady_to_s))
    steady_s = max(float(times[b] - times[a]), 1e-9)
    return WalkMeasures(
        distance_m=distance, mean_speed_mps=float(np.hypot(*(com[b, :2] - com[a, :2]))) / steady_s,
        overall_speed_mps=distance / max(clock.walking_s, 1e-9),
        lateral_drift_m=_drift(com[-1, :2], com[first, :2], travel),
        heading_error_deg=math.degrees(float(yaw[-1] - yaw[first]) - float(planned_yaw[-1] - planned_yaw[0])),
        turn_rate_deg_s=math.degrees(float(yaw[b] - yaw[a])) / steady_s,
        cop_inside_fraction=cop_inside_fraction(track, plan, first),
        worst_torque=worst_walk_torque(track, plan, spec, clock))
