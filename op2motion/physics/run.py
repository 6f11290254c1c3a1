"""The physics check, engine-independent: place the pose, ramp gravity in, hold or play the goals, watch.

Every engine offers the same few operations (``reset``, ``set_gravity``, ``state``, ``step``, ``base``,
``contacts``); this module runs the loop and judges, so a verdict means the same in every engine:

1. the first pose is placed on the floor (:func:`.body.placement`), at rest, with its joints where the servos'
   springs hold it still against gravity (:func:`op2motion.model.equilibrium.sagged_angles`) and gravity at full
   strength, so the start is neither an impact nor a transient; a walk (planned torso poses), a pose for which
   no such equilibrium exists, and one whose sag would press a swing foot into the floor (it was not standing on
   one leg) start at their goals instead while gravity rises from zero over :data:`RAMP_S`;
2. the first :data:`RAMP_S` is the loading window: the attitude at its end is what tilt counts from;
3. the servos hold the goals of the :class:`.schedule.Schedule` (one pose, or a motion's goals every 8 ms) for
   the rest of ``seconds``, optionally with a push at the torso's centre of mass;
4. every :data:`SAMPLE_S` the torso attitude, the centre of mass, the soles, the contacts and the servo torques
   are recorded; the last :data:`STEADY_S` is the steady window for torques, sag and centre of pressure.

Tilt and centre-of-mass drop are measured against the plan (where rigid servos would put the robot at that
moment), so a motion that turns the torso or crouches on purpose has not tilted or dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from op2motion.model.equilibrium import sagged_angles
from op2motion.model.servo import ServoModel
from op2motion.physics.body import Body, BodyState, placement
from op2motion.physics.schedule import Planned, Schedule, plan_rows
from op2motion.physics.verdict import (
    COM_DROP_FRACTION,
    CONTACT_FORCE_N,
    LIMIT_AT_RAD,
    LIMIT_AWAY_RAD,
    LIMIT_HOLD_S,
    LOADING_TILT_LIMIT_DEG,
    SATURATION_FRACTION,
    SATURATION_SHARE,
    SLIP_LIMIT_M,
    SLIP_LOAD_SHARE,
    SUPPORT_SETTLE_S,
    TILT_LIMIT_DEG,
    Failure,
    Validation,
)
from op2motion.robot.balance import convex_hull, polygon_margin
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, other_side

RAMP_S = 1.0
SAGGED_GAP_TOL_M = 1e-6    # the sagged start may leave a supporting foot this much higher than the rigid one
SAMPLE_S = 0.01
STEADY_S = 1.0


@dataclass(frozen=True)
class Push:
    """A force [N] (world frame) at the torso's centre of mass from ``start_s`` for ``duration_s`` [s]."""

    force: np.ndarray
    start_s: float
    duration_s: float


@dataclass
class _Track:
    """What the loop records at each sample."""

    times: list = field(default_factory=list)
    rot: list = field(default_factory=list)
    com: list = field(default_factory=list)
    soles: list = field(default_factory=list)
    q: list = field(default_factory=list)
    torque: list = field(default_factory=list)
    available: list = field(default_factory=list)
    cop: list = field(default_factory=list)
    feet: list = field(default_factory=list)          # per sample: {side: (vertical load [N], its own CoP [m])}
    ground: list = field(default_factory=list)
    self_pairs: list = field(default_factory=list)
    states: list = field(default_factory=list)
    rows: list = field(default_factory=list)          # the schedule row the servos held


def support_polygon_of(state: BodyState, support: str) -> np.ndarray:
    """The real support polygon (m, 2) [m]: the sole box of the support foot, or the hull of both soles."""
    return convex_hull(np.vstack([state.corners[side][:, :2] for side in Support.of(support).feet]))


def simulate(engine: Any, spec: Spec, servo: ServoModel, schedule: Schedule, seconds: float,
             push: Push | None = None, on_step: Callable[[], Any] | None = None,
             start_offset: np.ndarray | None = None) -> tuple[_Track, dict[str, Any]]:
    """Run one check (see the module docstring); returns the samples and the start facts. ``start_offset``
    (20,) [rad] starts the joints that far from their first goals (a perturbed start)."""
    body = Body(spec)
    q0, base_pos, base_rot, planned, ramp = _start(body, spec, servo, schedule)
    engine.reset(base_pos, base_rot, q0 + (0.0 if start_offset is None else start_offset))
    dt = engine.time_step
    steps = int(round(seconds / dt))
    every = max(1, int(round(SAMPLE_S / dt)))
    track = _Track()
    start = body.state(base_pos, base_rot, q0)
    push_steps = (range(0) if push is None else
                  range(int(round(push.start_s / dt)), int(round((push.start_s + push.duration_s) / dt))))
    for k in range(steps):
        t = k * dt
        if t <= RAMP_S + dt:
            engine.set_gravity(min(1.0, t / RAMP_S) if ramp else 1.0)
        row = schedule.row(t)
        q, dq = engine.state()
        engine.step(servo.active_torque(schedule.goals[row], q, schedule.kp[row]),
                    push.force if k in push_steps else None)
        if k % every == every - 1 or k == steps - 1:
            _sample(engine, body, servo, schedule, row, track, (k + 1) * dt)
        if on_step is not None:
            on_step()
    return track, {"start": start, "flat_foot": planned.flat_foot, "gap": planned.gap, "base_rot": base_rot,
                   "planned": planned}


def _start(body: Body, spec: Spec, servo: ServoModel, schedule: Schedule
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Planned, bool]:
    """Where a run starts: joint angles (20,) [rad], torso position [m] and rotation, the plan (with the start's
    flat foot and gap), and whether gravity must be ramped in. Statically sagged where an equilibrium exists and
    its sag leaves every foot meant to swing off the floor (see the module docstring); else the first goals."""
    base_pos, base_rot, planned = plan_rows(body, schedule)
    if schedule.base is None:
        q0 = sagged_angles(schedule.goals[0], schedule.supports[0], spec, schedule.kp[0], servo.torque_max)
        if q0 is not None:
            pos, rot, flat, gap = placement(body, q0, schedule.supports[0])
            if gap <= planned.gap + SAGGED_GAP_TOL_M:
                return q0, pos, rot, replace(planned, flat_foot=flat, gap=gap), False
    return schedule.goals[0], base_pos, base_rot, planned, True


def _sample(engine: Any, body: Body, servo: ServoModel, schedule: Schedule, row: int, track: _Track,
            t: float) -> None:
    q, dq = engine.state()
    pos, rot = engine.base()
    state = body.state(pos, rot, q)
    contacts = engine.contacts()
    ground = [c for c in contacts if c.other is None and c.normal_force > 0.0]
    load = sum(c.force[2] for c in ground)
    cop = (sum(c.force[2] * c.point[:2] for c in ground) / load) if load > 1e-6 else None
    feet = {}
    for side, link in body.foot_links.items():
        on = [c for c in ground if c.link == link]
        weight = sum(c.force[2] for c in on)
        if weight > 1e-6:
            feet[side] = (weight, sum(c.force[2] * c.point[:2] for c in on) / weight)
    pressed = {c.link: 0.0 for c in ground}
    for c in ground:
        pressed[c.link] += c.normal_force
    self_force: dict[tuple[str, str], float] = {}
    for c in contacts:
        if c.other is not None:
            pair = tuple(sorted((c.link, c.other)))
            self_force[pair] = self_force.get(pair, 0.0) + c.normal_force
    track.times.append(t)
    track.rot.append(rot)
    track.rows.append(row)
    track.com.append(state.com)
    track.soles.append({side: p for side, (p, _) in state.soles.items()})
    track.q.append(q)
    torque = servo.motor_torque(schedule.goals[row], q, dq, schedule.kp[row])
    track.torque.append(torque)
    track.available.append(servo.available(dq, torque))
    track.cop.append(cop)
    track.feet.append(feet)
    track.ground.append({link for link, f in pressed.items() if f > CONTACT_FORCE_N})
    track.self_pairs.append({pair for pair, f in self_force.items() if f > CONTACT_FORCE_N and pair[0] != pair[1]})
    track.states.append(state)


def _first_held(mask: np.ndarray, times: np.ndarray, hold_s: float) -> int | None:
    """Index of the first sample that starts a run of True lasting ``hold_s`` (or reaching the end)."""
    start = None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        elif not m:
            start = None
        if start is not None and (times[i] - times[start] >= hold_s - 1e-9 or i == len(mask) - 1 and
                                  times[i] - times[start] >= min(hold_s, STEADY_S) - 1e-9):
            return start
    return None


def first(mask: np.ndarray) -> int | None:
    """Index of the first true sample, or None."""
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else None


def _error_tilt_deg(planned_rot: np.ndarray, rot: np.ndarray, reference: np.ndarray) -> float:
    """How far the torso's up axis has turned [deg] from ``reference`` (an up axis in the planned torso frame),
    seen in the planned torso frame (a planned turn is not a tilt)."""
    up = planned_rot.T @ rot[:, 2]
    return math.degrees(math.acos(float(np.clip(up @ reference, -1.0, 1.0))))


def _slip(track: _Track, schedule: Schedule, start: BodyState, times: np.ndarray) -> tuple[float, int | None]:
    """The largest horizontal slide [m] of a foot while it supports and carries at least
    :data:`SLIP_LOAD_SHARE` of the load, from where it stood when that began (the start pose's soles for a support
    from the start), and the first sample beyond the limit."""
    worst, first_bad = 0.0, None
    for side in ("left", "right"):
        anchor = None
        for k, row in enumerate(track.rows):
            total = sum(w for w, _ in track.feet[k].values())
            carries = side in track.feet[k] and track.feet[k][side][0] >= SLIP_LOAD_SHARE * total
            if side not in Support.of(schedule.supports[row]).feet or (schedule.is_motion and not carries):
                anchor = None
                continue
            if anchor is None:
                anchor = start.soles[side][0][:2] if k == 0 else track.soles[k][side][:2]
            slide = float(np.hypot(*(track.soles[k][side][:2] - anchor)))
            worst = max(worst, slide)
            if slide > SLIP_LIMIT_M and (first_bad is None or k < first_bad):
                first_bad = k
    return worst, first_bad


def _motion_tilt(track: _Track, schedule: Schedule, plan_rot: np.ndarray, times: np.ndarray, loaded: int,
                 loaded_up: np.ndarray) -> np.ndarray:
    """Tilt [deg] of each sample from the plan, counted from the loaded attitude and again
    :data:`SUPPORT_SETTLE_S` after every change of support."""
    ups = np.array([plan_rot[k].T @ r[:, 2] for k, r in enumerate(track.rot)])
    reference, pending, out = loaded_up, None, np.zeros(len(times))
    for k in range(loaded, len(times)):
        if k > loaded and schedule.supports[track.rows[k]] != schedule.supports[track.rows[k - 1]]:
            pending = times[k] + SUPPORT_SETTLE_S
        if pending is not None and times[k] >= pending - 1e-9:
            reference, pending = ups[k], None
        out[k] = math.degrees(math.acos(float(np.clip(ups[k] @ reference, -1.0, 1.0))))
    return out


def sag_allowance_deg(schedule: Schedule, spec: Spec) -> float:
    """For a motion with single-support rows: the largest torso turn [deg] the compliance model predicts from the
    servos' sag on one leg (:mod:`op2motion.model.compliance`), by which a motion's tilt limit grows (its plan is
rigid);     0 for a held pose or a motion on two feet."""
    if not schedule.is_motion:
        return 0.0
    from op2motion.kinematics import forward
    from op2motion.model.compliance import Compliance
    from op2motion.robot.joints import servo_to_book

    model, worst = Compliance(spec), 0.0
    for side in ("left", "right"):
        rows = [k for k, s in enumerate(schedule.supports) if s == side]
        if rows:
            points = forward(servo_to_book(schedule.goals[rows], side, spec), spec, "dh", full_com=True)
            tilt = model.settle(points, points.com_full).tilt
            worst = max(worst, float(np.degrees(np.max(np.where(np.isfinite(tilt), tilt, 0.0)))))
    return worst


def judge(track: _Track, facts: dict[str, Any], spec: Spec, servo: ServoModel, schedule: Schedule,
          engine_name: str, dt: float, seconds: float) -> Validation:
    """The verdict and measurements of a recorded run (see :mod:`.verdict` for the reasons)."""
    times = np.asarray(track.times)
    rows = np.asarray(track.rows)
    planned: Planned = facts["planned"]
    loaded = int(min(np.searchsorted(times, RAMP_S), len(times) - 1))
    plan_rot = planned.rot[rows]
    # tilt counts from the loaded attitude (gravity at full strength): the sag while loading is not a fall; while
    # loading, a turn beyond LOADING_TILT_LIMIT_DEG from the start is. Both are seen from the plan.
    z = np.array([0.0, 0.0, 1.0])
    from_start = np.array([_error_tilt_deg(plan_rot[k], r, z) for k, r in enumerate(track.rot)])
    loaded_up = plan_rot[loaded].T @ track.rot[loaded][:, 2]
    tilt = _motion_tilt(track, schedule, plan_rot, times, loaded, loaded_up)
    load_tilt = float(from_start[loaded])
    loading_fall = first(from_start[:loaded] > LOADING_TILT_LIMIT_DEG)
    com = np.asarray(track.com)
    q, torque, available = np.asarray(track.q), np.abs(np.asarray(track.torque)), np.asarray(track.available)
    goals = schedule.goals[rows]
    start: BodyState = facts["start"]
    failures: list[Failure] = []
    foot_links = {spec.joint(f"{s[0]}_ank_roll").child: s for s in ("left", "right")}
    limit = TILT_LIMIT_DEG + sag_allowance_deg(schedule, spec)
    i = first(tilt > limit)
    if loading_fall is not None:
        i = loading_fall
    if i is not None:
        turned = max(float(tilt.max()), float(np.max(from_start)) - load_tilt)
        failures.append(Failure("tilt", times[i], f"the torso tilted {turned:.0f}° (limit {limit:.1f}° after "
                                                  f"loading)"))
    planned_com_z = np.array([planned.states[r].com[2] for r in rows])
    i = first(com[:, 2] < (1.0 - COM_DROP_FRACTION) * planned_com_z)
    if i is not None:
        failures.append(Failure("com_drop", times[i], f"the centre of mass sank to {com[i, 2]:.3f} m (planned "
                                                      f"{planned_com_z[i]:.3f} m)"))
    swing = [set(("left", "right")) - set(Support.of(schedule.supports[r]).feet) for r in rows]
    for reason, wanted in (("swing_foot_contact", lambda link, k: foot_links.get(link) in swing[k]),
                           ("ground_contact", lambda link, k: link not in foot_links)):
        hits = [(k, sorted(link for link in g if wanted(link, k))) for k, g in enumerate(track.ground)]
        hits = [(k, links) for k, links in hits if links]
        if hits:
            failures.append(Failure(reason, times[hits[0][0]], f"{', '.join(hits[0][1])} pressed on the floor"))
    hits = [(k, sorted(pairs)) for k, pairs in enumerate(track.self_pairs) if pairs]
    if hits:
        failures.append(Failure("self_collision", times[hits[0][0]],
                                "; ".join(" against ".join(p) for p in hits[0][1])))
    steady = times >= times[-1] - STEADY_S + 1e-9
    saturated = (torque / np.maximum(available, 1e-9) >= SATURATION_FRACTION)[steady].mean(axis=0)
    if saturated.max() >= SATURATION_SHARE:
        j = int(np.argmax(saturated))
        i = int(np.flatnonzero(steady)[0])
        failures.append(Failure("torque_saturation", times[i], f"{spec.joint_names[j]} needs "
                                                               f"{torque[steady][:, j].mean():.2f} N·m of "
                                                               f"{available[steady][:, j].mean():.2f} N·m available"))
    lower = np.array([j.mechanical[0] for j in spec.joints])
    upper = np.array([j.mechanical[1] for j in spec.joints])
    at_stop = ((q - lower < LIMIT_AT_RAD) | (upper - q < LIMIT_AT_RAD)) & (np.abs(q - goals) > LIMIT_AWAY_RAD)
    i = _first_held(np.any(at_stop, axis=1), times, LIMIT_HOLD_S)
    if i is not None:
        j = int(np.argmax(at_stop[i]))
        failures.append(Failure("joint_limit", times[i], f"{spec.joint_names[j]} lies on its stop at "
                                                         f"{math.degrees(q[i, j]):.1f}° "
                                                         f"(goal {math.degrees(goals[i, j]):.1f}°)"))
    slip, k = _slip(track, schedule, start, times)
    if k is not None:
        failures.append(Failure("slip", times[k], f"a supporting sole slid {slip * 1000:.0f} mm"))
    failures.sort(key=lambda f: f.time_s)
    mean_torque = torque[steady].mean(axis=0)
    worst = int(np.argmax(mean_torque / np.maximum(available[steady].mean(axis=0), 1e-9)))
    last = track.states[-1]
    final_support = schedule.supports[-1]
    margin = float(polygon_margin(com[-1, :2], support_polygon_of(last, final_support))[0])
    load_state = track.states[loaded]
    margin_load = float(polygon_margin(load_state.com[:2], support_polygon_of(load_state, schedule.supports[0]))[0])
    cops = [c for c, s in zip(track.cop, steady) if s and c is not None]
    reasons = list(dict.fromkeys(f.reason for f in failures))
    swing_side = other_side(final_support) if final_support != "double" else None
    return Validation(
        engine=engine_name, servo=servo.describe(), time_step_s=dt, seconds=seconds, stable=not failures,
        reasons=reasons, failures=failures, support_margin_m=round(margin, 5), margin_at_load_m=round(margin_load, 5),
        cop_xy=None if not cops else [round(float(v), 5) for v in np.mean(cops, axis=0)],
        com_settled=[round(float(v), 5) for v in com[-1]], com_start=[round(float(v), 5) for v in start.com],
        max_tilt_deg=round(float(tilt.max() if loading_fall is None else max(from_start)), 3),
        settled_tilt_deg=round(float(from_start[-1]), 3),
        load_tilt_deg=round(load_tilt, 3),
        com_drift_m=round(float(np.max(np.hypot(*(com[:, :2] - start.com[:2]).T))), 5), feet_slip_m=round(slip, 5),
        start_gap_m=round(facts["gap"], 5), flat_foot=facts["flat_foot"],
        self_collisions=[list(p) for p in sorted({p for pairs in track.self_pairs for p in pairs})],
        ground_contacts=sorted({link for g in track.ground for link in g}),
        max_torque_nm=round(float(mean_torque[worst]), 4),
        torque_ratio=round(float(mean_torque[worst] / max(available[steady][:, worst].mean(), 1e-9)), 4),
        worst_joint=spec.joint_names[worst], peak_torque_nm=round(float(torque.max()), 4),
        sag_deg={n: round(float(math.degrees(v)), 3)
                 for n, v in zip(spec.joint_names, (q[steady] - goals[steady]).mean(axis=0))},
        swing_foot_min_z_m=None if swing_side is None else round(float(last.corners[swing_side][:, 2].min()), 5),
        feet=_feet_report(track, steady, last),
        **_motion_report(track, schedule, spec, times, q, goals, torque, available))


def _motion_report(track: _Track, schedule: Schedule, spec: Spec, times: np.ndarray, q: np.ndarray,
                   goals: np.ndarray, torque: np.ndarray, available: np.ndarray) -> dict[str, Any]:
    """A motion's extras: tracking error per joint (goal - measured) while it plays and half a second after,
    the worst torque against what was available then, and the centre-of-pressure track."""
    if not schedule.is_motion:
        return {}
    playing = (times >= schedule.start_s) & (times <= schedule.end_s + 0.5)
    error = np.degrees(np.abs(goals[playing] - q[playing]))
    ratio = torque[playing] / np.maximum(available[playing], 1e-9)
    k, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    return {
        "tracking_max_deg": {n: round(float(v), 3) for n, v in zip(spec.joint_names, error.max(axis=0))},
        "tracking_rms_deg": {n: round(float(v), 3) for n, v in zip(spec.joint_names,
                                                                    np.sqrt((error ** 2).mean(axis=0)))},
        "motion_worst_torque": {"joint": spec.joint_names[j], "torque_nm": round(float(torque[playing][k, j]), 4),
                                "available_nm": round(float(available[playing][k, j]), 4),
                                "time_s": round(float(times[playing][k]), 3)},
        "cop_track": [[round(float(t), 3), round(float(c[0]), 5), round(float(c[1]), 5)]
                      for t, c in zip(times, track.cop) if c is not None],
    }


def _feet_report(track: _Track, steady: np.ndarray, last: BodyState) -> dict[str, dict[str, Any]]:
    """Each foot's share of the load and its own centre of pressure over the steady window, with the CoP's margin
    to that foot's sole [m] (a foot tips when its own CoP reaches its edge, whatever the other foot carries)."""
    out = {}
    samples = [f for f, s in zip(track.feet, steady) if s]
    total = sum(sum(w for w, _ in f.values()) for f in samples)
    for side in ("left", "right"):
        weights = np.array([f[side][0] for f in samples if side in f])
        if total <= 0.0 or weights.sum() <= 0.0:
            continue
        cop = sum(f[side][0] * f[side][1] for f in samples if side in f) / weights.sum()
        margin = float(polygon_margin(cop, convex_hull(last.corners[side][:, :2]))[0])
        out[side] = {"load_share": round(float(weights.sum() / total), 4),
                     "cop_xy": [round(float(v), 5) for v in cop], "cop_margin_m": round(margin, 5)}
    return out
