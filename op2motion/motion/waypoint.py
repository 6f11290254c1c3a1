"""A pose in a motion: what to reach, when, for how long, on which feet."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.framework import MAX_MOTION_POSES, MAX_MOTION_S, MAX_SEGMENT_S, MIN_SEGMENT_S
from op2motion.robot.support import Support

__all__ = ["MAX_SEGMENT_S", "MIN_SEGMENT_S", "Waypoint", "check_waypoints"]


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
    """Two to :data:`~op2motion.robot.framework.MAX_MOTION_POSES` poses; durations of 24 ms to a minute after the
    first; pauses of 0 to a minute; at most :data:`~op2motion.robot.framework.MAX_MOTION_S` in all."""
    if not 2 <= len(waypoints) <= MAX_MOTION_POSES:
        raise InputError(f"expected 2 to {MAX_MOTION_POSES} poses, got {len(waypoints)}", "poses")
    for k, w in enumerate(waypoints):
        if k and not (math.isfinite(w.duration_s) and MIN_SEGMENT_S - 1e-9 <= w.duration_s <= MAX_SEGMENT_S):
            raise InputError(f"expected {MIN_SEGMENT_S:.3f} to {MAX_SEGMENT_S:g} s to reach {w.name!r}, got "
                             f"{w.duration_s}", "durations")
        if not (math.isfinite(w.pause_s) and 0.0 <= w.pause_s <= MAX_SEGMENT_S):
            raise InputError(f"expected a pause of 0 to {MAX_SEGMENT_S:g} s at {w.name!r}, got {w.pause_s}", "pauses")
    total = sum(w.duration_s + w.pause_s for w in waypoints)
    if total > MAX_MOTION_S:
        raise InputError(f"expected a motion of at most {MAX_MOTION_S:g} s in all (durations and pauses), got "
                         f"{total:g} s", "durations")
