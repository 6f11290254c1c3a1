"""When a run may end before its plan's duration because its verdict is already known.

* **Settled**: after everything the plan and a push do (the last goal row sent, the push over, gravity at full
  strength) the robot has stayed still for :data:`SETTLE_HOLD_S`: every joint slower than
  :data:`SETTLED_JOINT_RAD_S`, the torso turning slower than :data:`SETTLED_GYRO_RAD_S` and moving slower than
  :data:`SETTLED_SPEED_M_S`. The run ends once the judge's steady window (the last :data:`.plan.STEADY_S`) lies wholly
  after those events, so torques, sag and the centre of pressure are measured on the same still robot as in a full
  run. A body that stays that still for that long is in equilibrium: one falling (an inverted pendulum, time
  constant about 0.15 s at the OP2's CoM height) speeds up 25-fold in that time. Only clear of the edge, though:
  the CoM must also lie :data:`EDGE_BAND_M` inside the support polygon, beyond what it would creep by the plan's
  end at the rate it crept over the window. At the lean sweeps' edges a pose 0.1 mm from its edge sat still for a
  second and then tipped over (an unstable equilibrium grows from almost nothing), and one-foot poses in PyBullet
  creep 0.3-0.4 mm/s towards their edge; those run the whole plan.
* **Fell**: the centre of mass sank below (1 - :data:`COM_DROP_FRACTION`) of its planned height, which the judge
  calls ``com_drop``: the verdict cannot change, and the failures before it (tilt, a foot or link on the floor) are
  already in the track.

Tests run the lean sweeps, stock pages and library poses both ways and compare the verdicts.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from op2motion.physics.plan import RAMP_S, STEADY_S, Plan

SETTLE_HOLD_S = 0.5            # still for this long: settled
SETTLED_JOINT_RAD_S = 0.05     # 2.9°/s
SETTLED_GYRO_RAD_S = 0.05      # 2.9°/s
SETTLED_SPEED_M_S = 0.005      # 5 mm/s: a one-leg pose in PyBullet sways 0.2 mm at about 2 Hz for seconds
EDGE_BAND_M = 0.005            # a settled CoM closer than this (plus its creep until the plan's end) to the support
                               # polygon's edge runs the whole plan: on the edge an equilibrium can tip slowly
COM_DROP_FRACTION = 0.25       # the judge's com_drop: the CoM this share below its planned height
FULL, SETTLED, FELL = "full", "settled", "fell"


class EarlyStop:
    """Watches one run (see the module docstring): :meth:`tick` every control period, :meth:`sample` at every
    recorded sample; ``ended`` says why the run ended (:data:`FULL`, :data:`SETTLED` or :data:`FELL`)."""

    def __init__(self, plan: Plan, ramped: bool, push_end_s: float = 0.0, enabled: bool = True):
        events = max(RAMP_S if ramped else 0.0, plan.end_s, push_end_s)
        self.duration_s = plan.duration_s
        # (t [s], the CoM's margin to the support [m], or how to work it out: most are never needed)
        self.margins: list[tuple[float, float | Callable[[], float]]] = []
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
        if self.enabled and t >= self.earliest_s and t - self.still_from >= SETTLE_HOLD_S - 1e-9 and self._clear(t):
            self.ended = SETTLED
            return True
        return False

    def _clear(self, t: float) -> bool:
        """The CoM is clear of the edge by :data:`EDGE_BAND_M` plus its creep until the plan ends."""
        window = [i for i, (s, _) in enumerate(self.margins) if s >= t - SETTLE_HOLD_S - 1e-9]
        if len(window) < 2:
            return False
        (t0, m0), (t1, m1) = self._margin(window[0]), self._margin(window[-1])
        creep = max(m0 - m1, 0.0) / max(t1 - t0, 1e-9)                   # [m/s] towards the edge
        return m1 > EDGE_BAND_M + creep * max(self.duration_s - t1, 0.0)

    def _margin(self, i: int) -> tuple[float, float]:
        """Sample ``i``'s time [s] and margin [m], worked out once."""
        t, margin = self.margins[i]
        if callable(margin):
            margin = margin()
            self.margins[i] = (t, margin)
        return t, margin

    def sample(self, t: float, com_z_m: float, planned_z_m: float, margin_m: float | Callable[[], float]) -> bool:
        """Record the CoM's margin [m] to the support at ``t`` [s] (or a function that works it out when needed);
        True when the run may end because it fell (the CoM height [m] against its planned height [m])."""
        self.margins.append((t, margin_m))
        if self.enabled and com_z_m < (1.0 - COM_DROP_FRACTION) * planned_z_m:
            self.ended = FELL
            return True
        return False
