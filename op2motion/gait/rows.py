"""The rows a walk controller plays: every 8 ms the planned joints, goals, torso, soles and what the feedback needs.

:class:`RowBuffer` holds them by absolute row number (row 0: the walk's first planned row, after the physics
lead-in). A planned :class:`~.generator.Gait` fills one buffer with all its rows at once (:func:`rows_of_gait`); the
rolling planner (:mod:`.rolling`) appends a chunk at a time and drops rows it no longer needs (:meth:`RowBuffer.trim`),
so a walk steered for an hour keeps a few seconds of rows, not an hour of them.

Numeric fields (:data:`NUMERIC`, one array per field, rows first) and per-row objects (:data:`OBJECTS`: the planned
contact, the physics support, what the step learner and the leg odometry need at that row).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from op2motion.errors import InputError
from op2motion.gait.generator import Gait
from op2motion.kinematics.leg_ik import Leg, leg_ik, rot_z, within_reach
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.support import SIDES, Side, Support

REACH_SHARE = 0.999                # a corrected leg stretches at most to this share of its length
#: Per-row numeric fields and the shape of one row of each (joints and goals in the spec's joint order [rad], P gains,
#: torso position [m] and rotation, soles (x, y, z [m], yaw [rad]), the swing's phase 0..1, the planned heading [rad]
#: (unwrapped), the planned stride velocity (2,) [m/s], the point the body turns about [m], each leg's planned servo
#: angles (6,) [rad], the ZMP reference and the multibody ZMP (2,) [m], the whole-body CoM (3,) [m], and 1 where the
#: row is played open loop (a kick inside a walk) else 0, and the share of the gyro damping servos stiffer than the
#: model keep (a steered walk standing still after walking takes it out: with stiff servos and sensor latency it kept a
#: standing robot rocking; :meth:`.controller.WalkController._standing_share`)).
NUMERIC = {"joints": (20,), "goals": (20,), "p_gains": (20,), "torso_pos": (3,), "torso_rot": (3, 3),
           "feet_left": (4,), "feet_right": (4,), "swing_phase": (), "plan_yaw": (), "velocity": (2,),
           "support_point": (3,), "legs_left": (6,), "legs_right": (6,), "zmp_ref": (2,), "zmp": (2,),
           "com": (3,), "open": (), "damping": ()}
#: Per-row objects: the planned contact ("left", "right", "double"), the physics support, the step learner's place
#: (swing side, row in the step, the step's number) or None, the leg odometry's landing (the foot stepped from, the
#: foot that landed, whether it closed the feet) or None.
OBJECTS = ("contact", "support", "learn", "landing")


class RowBuffer:
    """Rows by absolute number: :meth:`append` at the end, :meth:`trim` at the start (see the module docstring)."""

    def __init__(self, joints: int = 20):
        self.first = 0                                         # the absolute number of the oldest row kept
        shapes = {name: tuple(joints if s == 20 else s for s in shape) for name, shape in NUMERIC.items()}
        self.numeric = {name: np.zeros((0, *shape)) for name, shape in shapes.items()}
        self.objects: dict[str, list[Any]] = {name: [] for name in OBJECTS}

    @property
    def end(self) -> int:
        """One past the newest row's number."""
        return self.first + len(self.objects["contact"])

    def append(self, chunk: Mapping[str, Any]) -> None:
        """Add rows at the end: every field of :data:`NUMERIC` and :data:`OBJECTS`, one entry per row."""
        n = len(chunk["contact"])
        for name in NUMERIC:
            values = np.asarray(chunk[name], dtype=float)
            if len(values) != n:
                raise InputError(f"expected {n} rows of {name}, got {len(values)}", "rows")
            self.numeric[name] = np.concatenate([self.numeric[name], values])
        for name in OBJECTS:
            self.objects[name].extend(chunk[name])

    def trim(self, keep_from: int) -> None:
        """Forget the rows before ``keep_from`` (absolute)."""
        drop = max(0, min(keep_from, self.end) - self.first)
        if drop:
            for name in NUMERIC:
                self.numeric[name] = self.numeric[name][drop:]
            for name in OBJECTS:
                del self.objects[name][:drop]
            self.first += drop

    def truncate(self, end: int) -> None:
        """Forget the rows from ``end`` (absolute) on: a walk planned again from there (:mod:`.planned_stop`)."""
        keep = max(0, min(end, self.end) - self.first)
        for name in NUMERIC:
            self.numeric[name] = self.numeric[name][:keep]
        for name in OBJECTS:
            del self.objects[name][keep:]

    def _index(self, k: int) -> int:
        i = k - self.first
        if not 0 <= i < len(self.objects["contact"]):                  # (the rows kept: read every tick)
            raise InputError(f"expected a row from {self.first} to {self.end - 1}, got {k}", "row")
        return i

    def get(self, name: str, k: int) -> np.ndarray:
        """Row ``k`` of a numeric field."""
        row: np.ndarray = self.numeric[name][self._index(k)]
        return row

    def value(self, name: str, k: int) -> float:
        """Row ``k`` of a scalar numeric field."""
        return float(self.numeric[name][self._index(k)])

    def obj(self, name: str, k: int) -> Any:
        """Row ``k`` of an object field."""
        return self.objects[name][self._index(k)]

    def feet(self, side: Side, k: int) -> np.ndarray:
        """The ``side`` sole (x, y, z [m], yaw [rad]) at row ``k``."""
        return self.get(f"feet_{side}", k)

    def legs(self, side: Side, k: int) -> np.ndarray:
        """The ``side`` leg's planned servo angles (6,) [rad] at row ``k``."""
        return self.get(f"legs_{side}", k)

    def has(self, k: int) -> bool:
        """Is row ``k`` kept?"""
        return self.first <= k < self.end


def swing_phase(contact: tuple[str, ...]) -> np.ndarray:
    """Per row (K,): 0 -> 1 across each single-support phase (0 on both feet)."""
    phase = np.zeros(len(contact))
    start = 0
    for i in range(1, len(contact) + 1):
        if i == len(contact) or contact[i] != contact[start]:
            if contact[start] != "double":
                phase[start:i] = np.linspace(1.0 / (i - start), 1.0, i - start)
            start = i
    return phase


def support_points(feet: Mapping[str, np.ndarray], contact: tuple[str, ...]) -> np.ndarray:
    """The point (K, 3) [m] the body turns about at each row: the planned contact sole's centre, midway between the
    soles on two feet."""
    on = [Support.of(c).feet for c in contact]
    both = np.array([len(f) == 2 for f in on], dtype=bool).reshape(-1, 1)
    left_only = np.array([f == ("left",) for f in on], dtype=bool).reshape(-1, 1)
    left, right = feet["left"][:len(on), :3], feet["right"][:len(on), :3]
    return np.where(both, (left + right) / 2.0, np.where(left_only, left, right))  # the mean of one or two soles


def planned_legs(legs: Mapping[str, Leg], feet: Mapping[str, np.ndarray], pos: np.ndarray,
                 rot: np.ndarray) -> dict[str, np.ndarray]:
    """Each leg's servo angles (K, 6) [rad] that put its sole where the plan does (the reference the controller's
    corrections turn from), in one batch."""
    out = {}
    for side, leg in legs.items():
        sole = np.einsum("kji,kj->ki", rot, feet[side][:, :3] - pos)                    # rot.T @ (sole - pos)
        sole_rot = np.swapaxes(rot, 1, 2) @ rot_z(feet[side][:, 3])
        out[side] = leg_ik(leg, *within_reach(leg, sole, sole_rot, REACH_SHARE))
    return out


def torso_yaw(rot: np.ndarray, before: float | None = None) -> np.ndarray:
    """The torso's heading (K,) [rad] of rotations (K, 3, 3), unwrapped (turns pass ±180°), continuing from the
    heading ``before`` the first row if given."""
    yaw: np.ndarray = np.unwrap(np.arctan2(rot[:, 1, 0], rot[:, 0, 0]))
    if before is not None and len(yaw):
        yaw = yaw + 2.0 * math.pi * round((before - yaw[0]) / (2.0 * math.pi))
    return yaw


def stride_velocity(torso_pos: np.ndarray, rows_per_stride: int) -> np.ndarray:
    """Per row (K, 2): the torso velocity [m/s] averaged over a stride (two steps), the sway left out."""
    rows = max(1, rows_per_stride)
    velocity = np.gradient(torso_pos[:, :2], CONTROL_PERIOD_S, axis=0)
    kernel = np.ones(rows) / rows
    return np.stack([np.convolve(velocity[:, i], kernel, mode="same") for i in range(2)], axis=1)


def chunk_fields(legs: Mapping[str, Leg], feet: Mapping[str, np.ndarray], contact: tuple[str, ...],
                 pos: np.ndarray, rot: np.ndarray) -> dict[str, np.ndarray]:
    """The derived fields of a run of rows: swing phase, support points, planned legs, and the soles by field name."""
    fields = {"swing_phase": swing_phase(contact), "support_point": support_points(feet, contact)}
    for side, angles in planned_legs(legs, feet, pos, rot).items():
        fields[f"legs_{side}"] = angles
    for side in SIDES:
        fields[f"feet_{side}"] = feet[side]
    return fields


def rows_of_gait(gait: Gait, legs: Mapping[str, Leg]) -> RowBuffer:
    """All the rows of a planned gait in one buffer."""
    timeline = gait.timeline
    stride = int(round(2.0 * (gait.params.single_s + gait.params.double_s) / CONTROL_PERIOD_S))
    chunk = {"joints": gait.joints, "goals": gait.goals, "p_gains": gait.p_gains, "torso_pos": gait.torso_pos,
             "torso_rot": gait.torso_rot, "plan_yaw": torso_yaw(gait.torso_rot),
             "velocity": stride_velocity(gait.torso_pos, stride), "zmp_ref": timeline.zmp_ref, "zmp": gait.zmp,
             "com": gait.com, "contact": timeline.contact, "support": timeline.supports,
             "learn": [None] * len(gait.joints), "landing": [None] * len(gait.joints),
             "open": np.zeros(len(gait.joints)), "damping": np.ones(len(gait.joints)),
             **chunk_fields(legs, timeline.feet, timeline.contact, gait.torso_pos, gait.torso_rot)}
    rows = RowBuffer(gait.joints.shape[1])
    rows.append(chunk)
    return rows


def planned_zmp_margins(rows: RowBuffer, spec: Any, count: int) -> np.ndarray:
    """Margin [m] of each of the first ``count`` rows' planned (multibody) ZMP to the sole(s) of its planned contact
    (positive inside): :func:`~.footsteps.zmp_margins` of the buffer's rows."""
    from op2motion.gait.footsteps import zmp_margins

    ks = range(rows.first, rows.first + count)
    feet = {side: np.array([rows.feet(side, k) for k in ks]) for side in SIDES}
    return zmp_margins(np.array([rows.get("zmp", k) for k in ks]), [rows.obj("contact", k) for k in ks], feet, spec)
