"""Webots ``.motion`` and CSV exports of pose sequences.

Webots motion files (read by the Webots ``Motion`` class): a header ``#WEBOTS_MOTION,V1.0`` followed by the motor
names, then one line per pose ``mm:ss:mmm,PoseName,value,...`` with motor positions in radians. The ROBOTIS OP2
model in Webots uses the official joint axes and zeros, so its motor positions are op2motion's servo angles under
the Webots motor names of the spec.
"""

from __future__ import annotations

import csv
import io
import math
import re
from typing import Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, SupportName

MAX_TIME_S = 3600.0   # one pose per hour is the slowest sequence a table holds


def _check_time(seconds: float) -> None:
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_TIME_S):
        raise InputError(f"expected a number of seconds in (0, {MAX_TIME_S:g}], got {seconds}", "time")


def _stamp(t: float) -> str:
    ms = int(round(t * 1000))
    return f"{ms // 60000:02d}:{(ms // 1000) % 60:02d}:{ms % 1000:03d}"


def webots_name(name: str) -> str:
    """A pose name as a Webots motion line can carry it: letters, digits, ``_``, ``-`` and ``.`` (no commas, no
    line breaks)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "pose"


def webots_motion(poses: Sequence[Pose], spec: Spec, seconds: float = 1.0,
                  times: Sequence[float] | None = None) -> str:
    """Webots motion text: pose k is reached at k x ``seconds`` (the first at time 0), or at ``times`` [s]
    (strictly increasing on the file's millisecond clock)."""
    if times is None:
        _check_time(seconds)
        times = [k * seconds for k in range(len(poses))]
    return webots_rows(times, np.array([p.servo for p in poses]).reshape(len(poses), len(spec.joints)), spec,
                       [p.name for p in poses])


def webots_rows(times: Sequence[float] | np.ndarray, goals: np.ndarray, spec: Spec, names: Sequence[str]) -> str:
    """Webots motion text of servo rows (K, 20) [rad] reached at ``times`` [s] (strictly increasing on the file's
    millisecond clock, from 0), each line named by ``names``."""
    stamps = [int(round(t * 1000)) for t in times]
    if len(stamps) != len(goals) or any(b <= a for a, b in zip(stamps, stamps[1:])) or (stamps and stamps[0] < 0):
        raise InputError(f"expected {len(goals)} strictly increasing times from 0 (ms resolution), got "
                         f"{len(stamps)} times", "time")
    lines = ["#WEBOTS_MOTION,V1.0," + ",".join(j.webots for j in spec.joints)]
    for ms, name, row in zip(stamps, names, goals):
        lines.append(f"{_stamp(ms / 1000)},{webots_name(name)}," + ",".join(f"{q:.6f}" for q in row))
    return "\n".join(lines) + "\n"


def webots_warnings(poses: Sequence[Pose], spec: Spec) -> list[str]:
    """One line per pose with values outside the Webots model's motor stops (Webots clamps them)."""
    lo = np.array([j.webots_range[0] for j in spec.joints])
    hi = np.array([j.webots_range[1] for j in spec.joints])
    out = []
    for pose in poses:
        bad = [(j, q) for j, q, a, b in zip(spec.joints, pose.servo, lo, hi) if not a - 1e-9 <= q <= b + 1e-9]
        if bad:
            out.append(f"{pose.name}: outside the Webots robot's joint range (Webots clamps them): " + ", ".join(
                f"{j.webots} ({j.name}) {math.degrees(q):.1f}° not in [{math.degrees(j.webots_range[0]):.1f}, "
                f"{math.degrees(j.webots_range[1]):.1f}]°" for j, q in bad))
    return out


def csv_table(poses: Sequence[Pose], spec: Spec, seconds: float = 1.0) -> str:
    """CSV: one row per pose with its time, support, servo angles [deg] and goal ticks by joint name."""
    _check_time(seconds)
    names = spec.joint_names
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["name", "time_s", "support"] + [f"{n}_deg" for n in names] + [f"{n}_tick" for n in names])
    for k, pose in enumerate(poses):
        ticks = servo_to_ticks(pose.servo, spec)
        writer.writerow([pose.name, f"{k * seconds:.3f}", pose.support] + [f"{math.degrees(q):.4f}" for q in pose.servo]
                        + [str(int(t)) for t in ticks])
    return buf.getvalue()


def goals_csv(times: np.ndarray, goals: np.ndarray, supports: Sequence[Support | SupportName], spec: Spec) -> str:
    """CSV of a trajectory: one row per control tick with its time [s], support, goal angles [deg] and ticks."""
    names = spec.joint_names
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["time_s", "support"] + [f"{n}_deg" for n in names] + [f"{n}_tick" for n in names])
    for t, support, row in zip(times, supports, goals):
        writer.writerow([f"{t:.3f}", support] + [f"{math.degrees(q):.4f}" for q in row]
                        + [str(int(k)) for k in servo_to_ticks(row, spec)])
    return buf.getvalue()
