"""The verdict of a recorded run: one small function per failure reason (see :mod:`.report` for the vocabulary).

Each function reads plain arrays along the samples (times [s] and what was measured), so each can be tested on a
made-up track; :func:`failures` applies them all to a :class:`.track.Track` against its plan. Tilt and centre-of-mass
drop are measured against where rigid servos would put the robot at that moment (:func:`.plan.planned_states`), so a
motion that turns the torso or crouches on purpose has not tilted or dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from op2motion.physics.loop import StartFacts
from op2motion.physics.plan import RAMP_S, STEADY_S, Plan
from op2motion.physics.report import Failure
from op2motion.physics.stopping import COM_DROP_FRACTION
from op2motion.physics.track import Track
from op2motion.robot.spec import Spec

TILT_LIMIT_DEG = 10.0
LOADING_TILT_LIMIT_DEG = 20.0   # while gravity ramps in, a turn this large from the start is a fall
SATURATION_FRACTION = 0.95
SATURATION_SHARE = 0.5
FALL_LEAD_S = 0.2               # a fall's saturation is judged from this long before it began [s]
LIMIT_AT_RAD = 0.0175           # 1°: a joint this close to its stop lies on it
LIMIT_AWAY_RAD = 0.035          # 2°: ...and is held there away from its goal
LIMIT_HOLD_S = 0.2
SLIP_LIMIT_M = 0.01
SLIP_LOAD_SHARE = 0.2
SUPPORT_SETTLE_S = 0.3          # after a change of support, tilt is counted afresh this much later


def first(mask: np.ndarray) -> int | None:
    """Index of the first true sample, or None."""
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else None


def first_held(mask: np.ndarray, times: np.ndarray, hold_s: float) -> int | None:
    """Index of the first sample that starts a run of True lasting ``hold_s`` [s] (or reaching the end after at
    least ``min(hold_s, STEADY_S)``)."""
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


def steady_window(times: np.ndarray) -> np.ndarray:
    """The samples of the last :data:`STEADY_S` (bool (n,))."""
    steady: np.ndarray = times >= times[-1] - STEADY_S + 1e-9
    return steady


def tilt_failure(times: np.ndarray, tilt_deg: np.ndarray, from_start_deg: np.ndarray, loaded: int,
                 limit_deg: float) -> Failure | None:
    """``tilt``: after loading, the torso's turn ``tilt_deg`` (n,) beyond ``limit_deg``; while loading (samples
    before ``loaded``), its turn from the start ``from_start_deg`` (n,) beyond :data:`LOADING_TILT_LIMIT_DEG`."""
    loading_fall = first(from_start_deg[:loaded] > LOADING_TILT_LIMIT_DEG)
    i = loading_fall if loading_fall is not None else first(tilt_deg > limit_deg)
    if i is None:
        return None
    turned = max(float(tilt_deg.max()), float(np.max(from_start_deg)) - float(from_start_deg[loaded]))
    return Failure("tilt", float(times[i]), f"the torso tilted {turned:.0f}° (limit {limit_deg:.1f}° after loading)")


def com_drop_failure(times: np.ndarray, com_z: np.ndarray, planned_z: np.ndarray) -> Failure | None:
    """``com_drop``: the centre of mass (n,) [m] below (1 - :data:`COM_DROP_FRACTION`) of its planned height."""
    i = first(com_z < (1.0 - COM_DROP_FRACTION) * planned_z)
    if i is None:
        return None
    return Failure("com_drop", float(times[i]), f"the centre of mass sank to {com_z[i]:.3f} m (planned "
                                                f"{planned_z[i]:.3f} m)")


def floor_failures(times: np.ndarray, ground: Sequence[frozenset[str]], lifted: Sequence[frozenset[str]],
                   foot_links: Mapping[str, str]) -> list[Failure]:
    """``swing_foot_contact``: a foot meant to be lifted (``lifted``, sides per sample) pressed on the floor;
    ``ground_contact``: a link other than a foot (``foot_links``: link -> side) did."""
    def lifted_foot(link: str, k: int) -> bool:
        return foot_links.get(link) in lifted[k]

    def not_a_foot(link: str, k: int) -> bool:
        return link not in foot_links

    out = []
    for reason, wanted in (("swing_foot_contact", lifted_foot), ("ground_contact", not_a_foot)):
        hits = [(k, sorted(link for link in g if wanted(link, k))) for k, g in enumerate(ground)]
        hits = [(k, links) for k, links in hits if links]
        if hits:
            out.append(Failure(reason, float(times[hits[0][0]]), f"{', '.join(hits[0][1])} pressed on the floor"))
    return out


def self_collision_failure(times: np.ndarray, pairs: Sequence[frozenset[tuple[str, str]]]) -> Failure | None:
    """``self_collision``: the first sample with links pressing on each other."""
    k = next((k for k, p in enumerate(pairs) if p), None)
    if k is None:
        return None
    return Failure("self_collision", float(times[k]), "; ".join(" against ".join(p) for p in sorted(pairs[k])))


def fall_window(times: np.ndarray, fell_s: float, down_s: float | None) -> np.ndarray:
    """The samples from :data:`FALL_LEAD_S` before a fall began (``fell_s`` [s], its first tilt or drop) until the
    body was down (``down_s`` [s], its ``com_drop``; at most :data:`STEADY_S` after the start of the fall) (bool
    (n,)): what the servos did as the robot went down names the cause; what they do lying on the floor afterwards
    does not, and a check that stops early at the drop has exactly these samples."""
    end = fell_s + STEADY_S if down_s is None else down_s
    return (times >= fell_s - FALL_LEAD_S - 1e-9) & (times <= end + 1e-9)


def saturation_failure(times: np.ndarray, torque: np.ndarray, available: np.ndarray,
                       joint_names: Sequence[str], window: np.ndarray | None = None) -> Failure | None:
    """``torque_saturation``: over ``window`` (default the steady window; for a run that fell, the way down,
    :func:`fall_window`) a servo's torque |(n, 20)| [N·m] was at least :data:`SATURATION_FRACTION` of what
    was available in at least :data:`SATURATION_SHARE` of the samples."""
    steady = steady_window(times) if window is None else window
    if not steady.any():
        return None
    torque = np.abs(torque)
    saturated = (torque / np.maximum(available, 1e-9) >= SATURATION_FRACTION)[steady].mean(axis=0)
    if saturated.max() < SATURATION_SHARE:
        return None
    j = int(np.argmax(saturated))
    at = np.flatnonzero(steady)[0]
    if window is not None:         # on the way down: from when that servo first reached its limit
        at = np.flatnonzero(steady & (torque[:, j] / np.maximum(available[:, j], 1e-9) >= SATURATION_FRACTION))[0]
    return Failure("torque_saturation", float(times[at]),
                   f"{joint_names[j]} needs {torque[steady][:, j].mean():.2f} N·m of "
                   f"{available[steady][:, j].mean():.2f} N·m available")


def joint_limit_failure(times: np.ndarray, q: np.ndarray, goals: np.ndarray, limits: np.ndarray,
                        joint_names: Sequence[str]) -> Failure | None:
    """``joint_limit``: a joint (n, 20) [rad] within :data:`LIMIT_AT_RAD` of its stop (``limits`` (2, 20) [rad]),
    more than :data:`LIMIT_AWAY_RAD` from its goal, for :data:`LIMIT_HOLD_S`."""
    at_stop = (((q - limits[0] < LIMIT_AT_RAD) | (limits[1] - q < LIMIT_AT_RAD))
               & (np.abs(q - goals) > LIMIT_AWAY_RAD))
    i = first_held(np.any(at_stop, axis=1), times, LIMIT_HOLD_S)
    if i is None:
        return None
    j = int(np.argmax(at_stop[i]))
    return Failure("joint_limit", float(times[i]), f"{joint_names[j]} lies on its stop at {math.degrees(q[i, j]):.1f}° "
                                                   f"(goal {math.degrees(goals[i, j]):.1f}°)")


def slip(times: np.ndarray, soles_xy: Mapping[str, np.ndarray], supporting: Mapping[str, np.ndarray],
         start_xy: Mapping[str, np.ndarray]) -> tuple[float, Failure | None]:
    """The largest horizontal slide [m] of a sole (n, 2) while ``supporting`` (bool (n,)), from where it stood when
    that began (``start_xy`` for a support from the first sample), and ``slip`` where it passes
    :data:`SLIP_LIMIT_M`."""
    worst, first_bad = 0.0, None
    for side, xy in soles_xy.items():
        anchor, points, held = None, np.asarray(xy)[:, :2].tolist(), supporting[side]      # floats: per sample
        for k in range(len(times)):
            if not held[k]:
                anchor = None
                continue
            if anchor is None:
                anchor = [float(v) for v in start_xy[side][:2]] if k == 0 else points[k]
            slide = math.hypot(points[k][0] - anchor[0], points[k][1] - anchor[1])
            worst = max(worst, slide)
            if slide > SLIP_LIMIT_M and (first_bad is None or k < first_bad):
                first_bad = k
    if first_bad is None:
        return worst, None
    return worst, Failure("slip", float(times[first_bad]), f"a supporting sole slid {worst * 1000:.0f} mm")


def supporting_soles(track: Track, plan: Plan) -> dict[str, np.ndarray]:
    """Per side, the samples in which that sole supports: it is among its row's feet and (in a motion, where feet
    take and give up the load) carries at least :data:`SLIP_LOAD_SHARE` of the load."""
    out = {}
    for side in ("left", "right"):
        meant = np.array([side in plan.supports[r].feet for r in track.rows])
        if plan.is_motion:
            loads = [(f[side][0] if side in f else 0.0, sum(w for w, _ in f.values())) for f in track.feet]
            meant &= np.array([w > 0.0 and w >= SLIP_LOAD_SHARE * total for w, total in loads])
        out[side] = meant
    return out


@dataclass(frozen=True)
class Tilts:
    """The torso's turn [deg] from the planned attitude: ``from_start`` (n,), and ``tilt`` (n,) from the loaded
    attitude, counted afresh :data:`SUPPORT_SETTLE_S` after every change of support; ``loaded``: the loaded sample's
    index."""

    from_start: np.ndarray
    tilt: np.ndarray
    loaded: int


def tilts(track: Track, start: StartFacts, plan: Plan) -> Tilts:
    """The torso's :class:`Tilts` along a run."""
    times = track.times
    loaded = min(int(np.searchsorted(times, RAMP_S)), len(times) - 1)
    ups = np.einsum("kji,kj->ki", start.planned.rot[track.rows], track.rot[:, :, 2])   # up axis, planned frame
    from_start = np.degrees(np.arccos(np.clip(ups[:, 2], -1.0, 1.0)))
    reference, pending, tilt = ups[loaded], None, np.zeros(len(times))
    for k in range(loaded, len(times)):
        if k > loaded and plan.supports[track.rows[k]] != plan.supports[track.rows[k - 1]]:
            pending = times[k] + SUPPORT_SETTLE_S
        if pending is not None and times[k] >= pending - 1e-9:
            reference, pending = ups[k], None
        tilt[k] = math.degrees(math.acos(min(max(float(ups[k] @ reference), -1.0), 1.0)))
    return Tilts(from_start, tilt, loaded)


@dataclass(frozen=True)
class Judgement:
    """A judged run: its failures in the order they first happened, and what they were judged on: the torso's
    turn from the start and after loading (n,) [deg], the loaded sample, the largest supporting slide [m]."""

    failures: tuple[Failure, ...]
    from_start_deg: np.ndarray
    tilt_deg: np.ndarray
    loaded: int
    slip_m: float


def judge(track: Track, start: StartFacts, plan: Plan, spec: Spec, tilt_limit_deg: float) -> Judgement:
    """Every failure of a run (see the module docstring); tilt beyond ``tilt_limit_deg`` [deg] is a fall."""
    t = track.times
    turned = tilts(track, start, plan)
    from_start, tilt, loaded = turned.from_start, turned.tilt, turned.loaded
    planned_z = np.array([start.planned.states[r].com[2] for r in track.rows])
    foot_links = {link: side for side, link in _foot_links(spec).items()}
    lifted = [frozenset({"left", "right"} - set(plan.supports[r].feet)) for r in track.rows]
    limits = np.array([[j.mechanical[0] for j in spec.joints], [j.mechanical[1] for j in spec.joints]])
    start_xy = {side: start.state.soles[side][0][:2] for side in ("left", "right")}
    slid, slipped = slip(t, {s: xy[:, :2] for s, xy in track.soles.items()}, supporting_soles(track, plan), start_xy)
    fell = [f for f in (tilt_failure(t, tilt, from_start, loaded, tilt_limit_deg),
                        com_drop_failure(t, track.com[:, 2], planned_z)) if f is not None]
    down = next((f.time_s for f in fell if f.reason == "com_drop"), None)
    window = fall_window(t, min(f.time_s for f in fell), down) if fell else None   # a fall: judged on the way down
    found = [*fell, *floor_failures(t, track.ground, lifted, foot_links), self_collision_failure(t, track.self_pairs),
             saturation_failure(t, track.torque, track.available, spec.joint_names, window),
             joint_limit_failure(t, track.q, track.goals, limits, spec.joint_names), slipped]
    ordered = sorted((f for f in found if f is not None), key=lambda f: f.time_s)
    return Judgement(tuple(ordered), from_start, tilt, loaded, slid)


def _foot_links(spec: Spec) -> dict[str, str]:
    return {side: spec.joint(f"{side[0]}_ank_roll").child for side in ("left", "right")}
