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
from typing import Sequence

from ..errors import InputError
from ..joints import servo_to_ticks
from ..pose import Pose
from ..spec import Spec

MAX_TIME_S = 3600.0   # one pose per hour is the slowest sequence a table holds


def _check_time(seconds: float) -> None:
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_TIME_S):
        raise InputError(f"expected a number of seconds in (0, {MAX_TIME_S:g}], got {seconds}", "time")


def _stamp(t: float) -> str:
    ms = int(round(t * 1000))
    return f"{ms // 60000:02d}:{(ms // 1000) % 60:02d}:{ms % 1000:03d}"


def webots_motion(poses: Sequence[Pose], spec: Spec, seconds: float = 1.0) -> str:
    """Webots motion text: pose k is reached at k x ``seconds`` (the first at time 0)."""
    _check_time(seconds)
    lines = ["#WEBOTS_MOTION,V1.0," + ",".join(j.webots for j in spec.joints)]
    for k, pose in enumerate(poses):
        lines.append(f"{_stamp(k * seconds)},{pose.name}," + ",".join(f"{q:.6f}" for q in pose.servo))
    return "\n".join(lines) + "\n"


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
