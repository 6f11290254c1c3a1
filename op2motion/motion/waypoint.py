"""A pose in a motion: what to reach, when, for how long, on which feet."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.support import Support

MIN_SEGMENT_S = 3 * CONTROL_PERIOD_S   # the shortest step the robot moves (24 ms)
MAX_SEGMENT_S = 60.0


@dataclass(frozen=True)
class Waypoint:
    """A pose to reach: its name, servo angles (20,) [rad], the time to reach it from the previous one [s] (0 for
    the first), how long to hold it [s], and its support (``left``, ``right`` or ``double``); ``stop``: the motion
    comes to rest here even without a pause (else it flows through where a joint keeps its direction)."""

    name: str
    servo: np.ndarray
    duration_s: float
    pause_s: float
    support: Support
    stop: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "support", Support.of(self.support))


def check_waypoints(waypoints: Sequence[Waypoint]) -> None:
    """At least two poses; durations of 24 ms to a minute after the first; pauses of 0 to a minute."""
    if len(waypoints) < 2:
        raise InputError(f"expected at least two poses, got {len(waypoints)}", "poses")
    for k, w in enumerate(waypoints):
        if k and not (math.isfinite(w.duration_s) and MIN_SEGMENT_S - 1e-9 <= w.duration_s <= MAX_SEGMENT_S):
            raise InputError(f"expected {MIN_SEGMENT_S:.3f} to {MAX_SEGMENT_S:g} s to reach {w.name!r}, got "
                             f"{w.duration_s}", "durations")
        if not (math.isfinite(w.pause_s) and 0.0 <= w.pause_s <= MAX_SEGMENT_S):
            raise InputError(f"expected a pause of 0 to {MAX_SEGMENT_S:g} s at {w.name!r}, got {w.pause_s}", "pauses")
