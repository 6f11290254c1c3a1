"""Pose to pose: a sequence of poses with durations and pauses becomes joint goals every 8 ms.

Two profiles:

* ``quintic`` (joint space, the teach-pendant paper's approach): each segment is a quintic in time per joint, with
  zero acceleration at both ends; the velocity is zero at rest points (the first and last pose, a pose with a
  pause, a joint turning back) and, where a joint runs one way through a pose, the smaller of the two neighbouring
  segments' mean speeds, so the motion flows through it without overshooting;
* ``robot``: the poses become action-page steps (time and pause in 8 ms units, ≤ 2.04 s per step: longer segments
  are split into equal steps along the straight line) and the page player plays them exactly as the robot would
  (:mod:`.player`): its trapezoid profile.

The MX-28's speed is respected: a segment whose fastest joint would exceed :data:`SPEED_FRACTION` of the no-load
speed is stretched until it does not, and a note says so (the robot's own profile also has the framework's speed
clamp, 1023 units = 3.7 rad/s). Each row stands on the support its pose needs: a foot counts as supporting while
its lowest corner is within :data:`LIFTED_M` of the floor, with the other foot's sole level on it.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

from op2motion.errors import CheckFailed, InputError
from op2motion.formats.action import ActionFile
from op2motion.formats.actionlayout import MAX_BYTE, MAX_STEPS, NUM_PAGES, PageHeader, StepBytes, encode_page
from op2motion.formats.motionfile import PROFILES, PlannerName, Profile
from op2motion.motion.player import play, start_ticks, step_calls
from op2motion.motion.route import route, routed_clearance, with_stops
from op2motion.motion.shift import balanced, settled_swing_heights, with_weight_shifts
from op2motion.motion.trajectory import Trajectory, from_playback
from op2motion.motion.waypoint import Waypoint, check_waypoints
from op2motion.posture.cost import SELF_CLEARANCE_M
from op2motion.robot.framework import CONTROL_PERIOD_S, DEFAULT_P_GAIN, slope_of_p_gain
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.spec import Spec
from op2motion.robot.support import LIFTED_M, Support, SupportName

SPEED_FRACTION = 0.5       # of the no-load speed: at the peak speed half the stall torque is still available
_FIRST_PAGE = 1


def _units(seconds: float) -> int:
    return max(1, int(math.ceil(seconds / CONTROL_PERIOD_S - 1e-9)))


def _through_velocities(q: np.ndarray, durations: np.ndarray, rests: np.ndarray) -> np.ndarray:
    """Velocity [rad/s] (n, 20) at each waypoint: 0 at rest points (``rests`` (n,) bool), else the smaller
    neighbouring mean speed."""
    v = np.zeros_like(q)
    for i in range(1, len(q) - 1):
        if rests[i]:
            continue
        before = (q[i] - q[i - 1]) / durations[i]
        after = (q[i + 1] - q[i]) / durations[i + 1]
        one_way = np.sign(before) == np.sign(after)
        v[i] = np.where(one_way & (before != 0.0), np.sign(before) * np.minimum(abs(before), abs(after)), 0.0)
    return v


def _quintic(q0: np.ndarray, q1: np.ndarray, v0: np.ndarray, v1: np.ndarray, length: float,
             t: np.ndarray) -> np.ndarray:
    """Positions (len(t), 20) of quintics from (q0, v0, 0) to (q1, v1, 0) over ``length`` [s] at times ``t``."""
    h = q1 - q0
    c3 = (20 * h - (8 * v1 + 12 * v0) * length) / (2 * length ** 3)
    c4 = (-30 * h + (14 * v1 + 16 * v0) * length) / (2 * length ** 4)
    c5 = (12 * h - 6 * (v1 + v0) * length) / (2 * length ** 5)
    t = t[:, None]
    q: np.ndarray = q0 + v0 * t + c3 * t ** 3 + c4 * t ** 4 + c5 * t ** 5
    return q


def _peak_speed(q0: np.ndarray, q1: np.ndarray, v0: np.ndarray, v1: np.ndarray, length: float) -> np.ndarray:
    t = np.linspace(0.0, length, 65)
    peak: np.ndarray = np.abs(np.gradient(_quintic(q0, q1, v0, v1, length, t), t, axis=0)).max(axis=0)
    return peak


def _timed(waypoints: Sequence[Waypoint], v_max: float, peak: Callable[[np.ndarray], np.ndarray]
           ) -> tuple[np.ndarray, list[str]]:
    """Durations [s] (n,) in whole 8 ms units, stretched until no joint exceeds ``v_max``; notes on each stretch."""
    asked = np.array([0.0] + [_units(w.duration_s) * CONTROL_PERIOD_S for w in waypoints[1:]])
    durations = asked.copy()
    for _ in range(8):
        speeds = peak(durations)                       # (n - 1, 20) peak speed of each segment per joint
        over = speeds.max(axis=1) > v_max * (1 + 1e-6)
        if not over.any():
            break
        durations[1:] = np.where(over, _units_array(durations[1:] * speeds.max(axis=1) / v_max) * CONTROL_PERIOD_S,
                                 durations[1:])
    notes = []
    for i in map(int, np.flatnonzero(durations[1:] > asked[1:] + 1e-9) + 1):
        notes.append(f"{waypoints[i - 1].name} -> {waypoints[i].name}: stretched from {asked[i]:.3f} s to "
                     f"{durations[i]:.3f} s to keep every joint under {v_max:.2f} rad/s "
                     f"({SPEED_FRACTION:.0%} of the MX-28's no-load speed)")
    return durations, notes


def blend(q0: np.ndarray, q1: np.ndarray, spec: Spec, least_s: float = CONTROL_PERIOD_S) -> np.ndarray:
    """Goals (K, 20) [rad] every 8 ms from ``q0`` to ``q1`` (rest to rest), a quintic as long as the fastest joint
    needs to stay within :data:`SPEED_FRACTION` of the no-load speed, at least ``least_s`` [s]; the first row is
    the row after ``q0``, the last is ``q1``."""
    q0, q1 = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    v_max = SPEED_FRACTION * spec.servo.no_load_speed_rad_s
    length = _units(max(least_s, 1.875 * float(np.max(np.abs(q1 - q0), initial=0.0)) / v_max)) * CONTROL_PERIOD_S
    t = np.arange(1, int(round(length / CONTROL_PERIOD_S)) + 1) * CONTROL_PERIOD_S
    zero = np.zeros_like(q0)
    return _quintic(q0, q1, zero, zero, length, t)


def _units_array(seconds: np.ndarray) -> np.ndarray:
    return np.maximum(1, np.ceil(seconds / CONTROL_PERIOD_S - 1e-9))


def _quintic_rows(waypoints: Sequence[Waypoint], v_max: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    q = np.array([w.servo for w in waypoints])
    pauses = np.array([w.pause_s for w in waypoints])
    rests = np.array([w.pause_s > 0.0 or w.stop for w in waypoints])

    def peak(durations: np.ndarray) -> np.ndarray:
        v = _through_velocities(q, durations, rests)
        return np.array([_peak_speed(q[i], q[i + 1], v[i], v[i + 1], durations[i + 1]) for i in range(len(q) - 1)])

    durations, notes = _timed(waypoints, v_max, peak)
    v = _through_velocities(q, durations, rests)
    rows, segment = [q[:1]], [-1]
    if pauses[0] > 0:
        rows.append(np.repeat(q[:1], _units(pauses[0]), axis=0))
        segment += [0] * _units(pauses[0])
    for i in range(len(q) - 1):
        n = int(round(durations[i + 1] / CONTROL_PERIOD_S))
        t = np.arange(1, n + 1) * CONTROL_PERIOD_S
        part = _quintic(q[i], q[i + 1], v[i], v[i + 1], durations[i + 1], t)
        part[-1] = q[i + 1]                            # land exactly on the pose
        rows.append(part)
        hold = int(round(pauses[i + 1] / CONTROL_PERIOD_S)) if pauses[i + 1] > 0 else 0
        if hold:
            rows.append(np.repeat(q[i + 1:i + 2], hold, axis=0))
        segment += [i] * (n + hold)
    return np.vstack(rows), np.array(segment), notes


def robot_steps(waypoints: Sequence[Waypoint], spec: Spec, v_max: float
                ) -> tuple[list[StepBytes], list[str], list[int]]:
    """Action-page steps for the poses after the first: each segment split into equal steps of at most 2.04 s
    along the straight line, stretched for the speed limit, a long pause held by steps that stay put; goal words
    for IDs 1-20; the notes; the segment of each step."""
    q = np.array([w.servo for w in waypoints])

    def peak(durations: np.ndarray) -> np.ndarray:     # a trapezoid with ramps of a quarter: 4/3 of the mean speed
        return np.array([abs(q[i + 1] - q[i]) / durations[i + 1] * 4 / 3 for i in range(len(q) - 1)])

    durations, notes = _timed(waypoints, v_max, peak)
    steps, owner = [], []
    for i in range(1, len(q)):
        units = int(round(durations[i] / CONTROL_PERIOD_S))
        parts = int(math.ceil(units / MAX_BYTE))
        for k in range(1, parts + 1):
            ticks = servo_to_ticks(q[i - 1] + (q[i] - q[i - 1]) * k / parts, spec)
            steps.append(StepBytes({j.id: int(t) for j, t in zip(spec.joints, ticks)}, 0, int(round(units / parts))))
            owner.append(i - 1)
        hold = _units(waypoints[i].pause_s) if waypoints[i].pause_s > 0 else 0
        while hold > 0:                                # a pause longer than a byte: steps that stay put
            last = steps[-1]
            steps[-1] = StepBytes(last.words, min(hold, MAX_BYTE), last.time)
            hold -= min(hold, MAX_BYTE)
            if hold > 0:
                steps.append(StepBytes(last.words, 0, min(hold, MAX_BYTE)))
                owner.append(i - 1)
                hold -= min(hold, MAX_BYTE)
    return steps, notes, owner


def robot_pages(name: str, steps: Sequence[StepBytes], first_page: int = _FIRST_PAGE,
                slopes: dict[int, int] | None = None) -> list[bytes]:
    """The steps as chained pages of at most 7 steps each (``next`` links them), from ``first_page`` on."""
    chunks = [steps[i:i + MAX_STEPS] for i in range(0, len(steps), MAX_STEPS)]
    if first_page + len(chunks) - 1 >= NUM_PAGES:
        raise InputError(f"{len(chunks)} pages from page {first_page} do not fit in pages 1..{NUM_PAGES - 1}",
                         "page")
    return [encode_page(f"{name[:10]}{k + 1}" if len(chunks) > 1 else name, chunk,
                        PageHeader(next=first_page + k + 1 if k + 1 < len(chunks) else 0, slopes=slopes))
            for k, chunk in enumerate(chunks)]


def _robot_rows(waypoints: Sequence[Waypoint], spec: Spec, v_max: float) -> tuple[np.ndarray, np.ndarray,
                                                                                   list[str], np.ndarray]:
    steps, notes, owner = robot_steps(waypoints, spec, v_max)
    action = ActionFile.blank().with_pages(robot_pages("motion", steps), _FIRST_PAGE).action
    played = from_playback(play(action, _FIRST_PAGE, start_ticks(waypoints[0].servo, spec)), spec)
    # the segment of each row, from the calls each step takes (the first call prepares the first step)
    bounds = 1 + np.cumsum([step_calls(s.time, s.pause) for s in steps])
    step_of = np.minimum(np.searchsorted(bounds, np.arange(len(played.goals)), side="right"), len(steps) - 1)
    segment = np.asarray(owner)[step_of]
    segment[0] = -1
    return played.goals, segment, notes, played.p_gains


def row_supports(goals: np.ndarray, segment: np.ndarray, waypoints: Sequence[Waypoint],
                 spec: Spec) -> tuple[Support | SupportName, ...]:
    """The support of each row: a single-support segment end's foot stands; the other foot supports too while
    its lowest corner, after the sag, is within :data:`LIFTED_M` of the floor."""
    out: list[Support | SupportName] = []
    heights = {side: settled_swing_heights(goals, side, spec) for side in ("left", "right")}
    for k, seg in enumerate(segment):
        ends = [waypoints[0]] if seg < 0 else [waypoints[seg], waypoints[seg + 1]]
        singles = {w.support for w in ends if not w.support.is_double}
        if not singles:
            out.append("double")
            continue
        stand = sorted(singles)[0] if len(singles) == 1 else ends[0].support
        out.append("double" if heights[stand][k] < LIFTED_M else stand)
    return tuple(out)


def _rows(waypoints: Sequence[Waypoint], spec: Spec, profile: Profile, p_gain: int
          ) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray]:
    """Goals (K, 20), the segment of each row, the timing notes and the P gains (K, 20) of ``profile``."""
    v_max = SPEED_FRACTION * spec.servo.no_load_speed_rad_s
    if profile == "quintic":
        goals, segment, notes = _quintic_rows(waypoints, v_max)
        return balanced(goals, segment, waypoints, spec), segment, notes, np.full(goals.shape, float(p_gain))
    return _robot_rows(waypoints, spec, v_max)


def trajectory_through(waypoints: Sequence[Waypoint], spec: Spec, profile: Profile = "quintic",
                       p_gain: int = DEFAULT_P_GAIN, shift_weight: bool = True, planner: PlannerName = "rrt",
                       seed: int = 0) -> Trajectory:
    """Joint goals every 8 ms through ``waypoints`` with ``profile`` (``quintic`` or ``robot``); with
    ``shift_weight``, a weight shift goes in wherever the sequence changes between two feet and one; with
    ``planner`` "rrt", a segment whose straight line collides is planned around (:mod:`.route`, seeded by
    ``seed``): the motion flows through the via poses where that keeps every row
    :data:`~.body_checks.SELF_CLEARANCE_M` clear, else it comes to rest at each."""
    check_waypoints(waypoints)
    if profile not in PROFILES:
        raise InputError(f"expected one of {', '.join(PROFILES)}, got {profile!r}", "profile")
    shift_notes: list[str] = []
    if shift_weight:
        waypoints, shift_notes = with_weight_shifts(waypoints, spec)
    routed = route(waypoints, spec, planner, seed)
    waypoints = routed.waypoints
    goals, segment, notes, gains = _rows(waypoints, spec, profile, p_gain)
    if routed.segments and routed_clearance(goals, segment, routed, spec) < SELF_CLEARANCE_M:
        waypoints = with_stops(routed)
        goals, segment, notes, gains = _rows(waypoints, spec, profile, p_gain)
        least = routed_clearance(goals, segment, routed, spec)
        if least < SELF_CLEARANCE_M:
            raise CheckFailed(f"the planned path keeps only {least * 1000:.1f} mm between links once timed (expected "
                              f"at least {SELF_CLEARANCE_M * 1000:.0f} mm): try another --seed")
        notes.append("the motion comes to rest at each via pose (flowing through them came too close)")
    names = tuple(f"{a.name} -> {b.name}" for a, b in zip(waypoints, waypoints[1:]))
    return Trajectory(goals, gains, row_supports(goals, segment, waypoints, spec), segment, names,
                      notes=tuple(shift_notes + routed.notes + notes))


def action_pages(waypoints: Sequence[Waypoint], spec: Spec, name: str, first_page: int,
                 p_gain: int = DEFAULT_P_GAIN, shift_weight: bool = True, planner: PlannerName = "rrt",
                 seed: int = 0) -> tuple[list[bytes], list[str]]:
    """The motion as chained action pages from ``first_page`` on (the robot's profile: what the robot plays),
    weight shifts inserted and colliding segments planned around as :func:`trajectory_through` does, every joint's
    slope set for ``p_gain``; and the notes."""
    check_waypoints(waypoints)
    notes: list[str] = []
    if shift_weight:
        waypoints, notes = with_weight_shifts(waypoints, spec)
    routed = route(waypoints, spec, planner, seed)
    waypoints, notes = routed.waypoints, notes + routed.notes
    steps, timing, _ = robot_steps(waypoints, spec, SPEED_FRACTION * spec.servo.no_load_speed_rad_s)
    slopes = {j.id: slope_of_p_gain(p_gain) for j in spec.joints} if p_gain != DEFAULT_P_GAIN else None
    return robot_pages(name, steps, first_page, slopes), notes + timing
