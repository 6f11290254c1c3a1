"""Where did the feet land? Leg odometry from the measured joints, and what the walk does about it.

At every landing (a few rows into the double support that follows a single support, when the joint readings show
the foot down) :class:`FootOdometry` takes both soles from the measured leg angles (:func:`.leg_ik.leg_fk`), the
landed foot against the one it stepped from in that foot's frame, and compares with the plan. The misses add up to
the feet's running placement error in the plan's frame (x forward, y left of the walk's start). Two uses:

* **keeping the line**: the swing foot is moved against ``gain`` times the part of that error across the planned
  direction of travel (all of it where the plan does not travel), phased in over the swing, at most
  :data:`MAX_PLACEMENT_M`. Along the path is the walk's pace, not its line: correcting it too lengthened the
  steps of the bodies that already leaned forward (more falls). Side steps that land short or long (the heading
  loop does not see them) and turns in place that wander are brought back;
* **accepting the last landing**: after the closing step no step follows to correct a miss, and in the final double
  support the legs pulled the feet towards the planned stance, which twisted the whole body (5–7° of heading in
  the stiff-servo members of the robustness family). From the measurement on, the landed foot's target is where
  it landed (position and yaw).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from op2motion.gait.generator import Gait
from op2motion.kinematics.leg_ik import Leg, leg_fk, rot_z
from op2motion.robot.support import Side, SupportName

MAX_PLACEMENT_M = 0.02      # a swing foot is moved at most this far from its plan to keep the line
MIN_TRACK_SPEED_M_S = 0.02  # below this planned speed there is no direction of travel


def landing_rows(contact: tuple[SupportName, ...], after: int) -> dict[int, tuple[Side, Side]]:
    """Per landing, the gait row to measure it (``after`` rows into the double support that follows a single
    support, at most its last row): (the foot stepped from, the foot that landed)."""
    out: dict[int, tuple[Side, Side]] = {}
    i = 1
    while i < len(contact):
        stance = contact[i - 1]
        if contact[i] == "double" and stance != "double":
            end = i
            while end + 1 < len(contact) and contact[end + 1] == "double":
                end += 1
            out[min(i + after, end)] = (stance, "left" if stance == "right" else "right")
            i = end + 1
        else:
            i += 1
    return out


def left_of(velocity: np.ndarray) -> np.ndarray | None:
    """The unit vector (2,) to the left of a planned velocity (2,) [m/s]; None below :data:`MIN_TRACK_SPEED_M_S`
    (no direction of travel)."""
    speed = float(np.hypot(*velocity))
    return None if speed <= MIN_TRACK_SPEED_M_S else np.array([-velocity[1], velocity[0]]) / speed


def across(error: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    """The part (2,) of a plan-frame error [m] across a planned velocity (2,) [m/s] (all of it below
    :data:`MIN_TRACK_SPEED_M_S`)."""
    normal = left_of(velocity)
    return error if normal is None else float(error @ normal) * normal


@dataclass
class FootOdometry(ABC):
    """The feet's placement error from the measured joints (see the module docstring); where the landings are is the
    kind of walk's (:meth:`observe`: :class:`PlannedOdometry` from a whole plan,
    :class:`~.steer_feedback.RollingOdometry` from the rows as they are planned).

    Attributes:
        legs: per side, the leg's geometry.
        error: the feet's running placement error (2,) [m], plan frame.
        last: after the closing step is measured, (the landed side, its position miss (2,) [m], yaw miss [rad]).
    """

    legs: dict[str, Leg]
    error: np.ndarray = field(default_factory=lambda: np.zeros(2))
    last: tuple[str, np.ndarray, float] | None = None

    def reset(self) -> None:
        """Forget the measurements."""
        self.error, self.last = np.zeros(2), None

    @abstractmethod
    def observe(self, k: int, measured: np.ndarray) -> None:
        """Walk row ``k``'s joint angles (20,) [rad]: measure a landing that is due there."""

    def _landing(self, measured: np.ndarray, stance: Side, landed: str, stance_plan: np.ndarray,
                 landed_plan: np.ndarray, closing: bool) -> None:
        """One landing measured: the ``landed`` foot against the ``stance`` one from the joints (20,) [rad], less
        the plan's soles (x, y, z [m], yaw [rad]); a ``closing`` landing's miss is kept in :attr:`last`."""
        (p0, r0), (p1, r1) = (leg_fk(self.legs[side], measured[list(self.legs[side].index)])
                              for side in (stance, landed))
        yaw = float(stance_plan[3])
        actual = (r0[0].T @ (p1[0] - p0[0]))[:2]
        planned = (rot_z(yaw).T @ (landed_plan[:3] - stance_plan[:3]))[:2]
        miss = rot_z(yaw)[:2, :2] @ (actual - planned)
        self.error = self.error + miss
        if closing:
            turned = r0[0].T @ r1[0]
            yaw_miss = math.atan2(turned[1, 0], turned[0, 0]) - (float(landed_plan[3]) - yaw)
            self.last = (landed, miss, math.remainder(yaw_miss, 2.0 * math.pi))

    def shift(self, gain: float, velocity: np.ndarray) -> np.ndarray:
        """The swing foot's move (3,) [m] against the error across ``velocity`` (2,) [m/s], bounded."""
        move = -gain * across(self.error, velocity)
        norm = float(np.hypot(*move))
        if norm > MAX_PLACEMENT_M:
            move = move * (MAX_PLACEMENT_M / norm)
        return np.array([move[0], move[1], 0.0])


@dataclass(kw_only=True)
class PlannedOdometry(FootOdometry):
    """The :class:`FootOdometry` of a planned gait: ``rows``, per measuring row, (the foot stepped from, the foot
    that landed)."""

    gait: Gait
    rows: dict[int, tuple[Side, Side]]

    @classmethod
    def of(cls, gait: Gait, legs: dict[str, Leg], after: int) -> "PlannedOdometry":
        """The odometry of ``gait``, each landing measured ``after`` rows into its double support."""
        return cls(dict(legs), gait=gait, rows=landing_rows(gait.timeline.contact, after))

    def observe(self, k: int, measured: np.ndarray) -> None:
        """At a measuring row ``k``, the joint angles (20,) [rad]: add the landing's miss to the running error."""
        if k not in self.rows:
            return
        stance, landed = self.rows[k]
        feet = self.gait.timeline.feet
        self._landing(measured, stance, landed, feet[stance][k], feet[landed][k], k == max(self.rows))
