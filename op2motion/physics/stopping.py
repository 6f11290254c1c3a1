"""When a run may end before its plan's duration because its verdict is already known.

* **Settled**: after everything the plan and a push do (the last goal row sent, the push over, gravity at full
  strength) the robot has stayed still for :data:`SETTLE_HOLD_S`: every joint slower than
  :data:`SETTLED_JOINT_RAD_S`, the torso turning slower than :data:`SETTLED_GYRO_RAD_S` and moving slower than
  :data:`SETTLED_SPEED_M_S`. The run ends once the judge's steady window (the last :data:`.plan.STEADY_S`) lies wholly
  after those events, so torques, sag and the centre of pressure are measured on the same still robot as in a full
  run. A body that stays that still for that long is in equilibrium: one falling (an inverted pendulum, time
  constant about 0.15 s at the OP2's CoM height) speeds up 25-fold in that time.
* **Fell**: the centre of mass sank below (1 - :data:`COM_DROP_FRACTION`) of its planned height, which the judge
  calls ``com_drop``: the verdict cannot change, and the failures before it (tilt, a foot or link on the floor) are
  already in the track.

Tests run the lean sweeps, stock pages and library poses both ways and compare the verdicts.
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.physics.plan import RAMP_S, STEADY_S, Plan

SETTLE_HOLD_S = 0.5            # still for this long: settled
SETTLED_JOINT_RAD_S = 0.05     # 2.9°/s
SETTLED_GYRO_RAD_S = 0.05      # 2.9°/s
SETTLED_SPEED_M_S = 0.005      # 5 mm/s: a one-leg pose in PyBullet sways 0.2 mm at about 2 Hz for seconds
COM_DROP_FRACTION = 0.25       # the judge's com_drop: the CoM this share below its planned height
FULL, SETTLED, FELL = "full", "settled", "fell"


class EarlyStop:
    """Watches one run (see the module docstring): :meth:`tick` every control period, :meth:`sample` at every
    recorded sample; ``ended`` says why the run ended (:data:`FULL`, :data:`SETTLED` or :data:`FELL`)."""

    def __init__(self, plan: Plan, ramped: bool, push_end_s: float = 0.0, enabled: bool = True):
        events = max(RAMP_S if ramped else 0.0, plan.end_s, push_end_s)
        self.earliest_s = max(events + STEADY_S, events + SETTLE_HOLD_S, RAMP_S)
        self.events_s, self.enabled = events, enabled
        self.still_from: float | None = None
        self.ended = FULL

    def tick(self, t: float, joint_speeds: np.ndarray, angular: np.ndarray, linear: np.ndarray) -> bool:
        """True when the run may end at ``t`` [s] because it has settled (speeds [rad/s], torso [rad/s], [m/s])."""
        still = (t >= self.events_s and float(np.max(np.abs(joint_speeds))) < SETTLED_JOINT_RAD_S
                 and math.hypot(*angular) < SETTLED_GYRO_RAD_S and math.hypot(*linear) < SETTLED_SPEED_M_S)
        if not still:
            self.still_from = None
            return False
        if self.still_from is None:
            self.still_from = t
        if self.enabled and t >= self.earliest_s and t - self.still_from >= SETTLE_HOLD_S - 1e-9:
            self.ended = SETTLED
            return True
        return False

    def sample(self, com_z_m: float, planned_z_m: float) -> bool:
        """True when the run may end because it fell (the CoM height [m] against its planned height [m])."""
        if self.enabled and com_z_m < (1.0 - COM_DROP_FRACTION) * planned_z_m:
            self.ended = FELL
            return True
        return False
