"""Is the body still? From what a controller reads every 8 ms: the torso's gyro and the joint angles.

The gyro is low-passed (:data:`GYRO_TAU_S`: a real OP2's gyro counts 0.055 rad/s apiece, so one sample says little)
and must stay below :data:`STILL_GYRO_RAD_S`; every joint must stay within :data:`STILL_JOINT_RAD` of where it was
:data:`WINDOW_S` before (one encoder tick, 0.0015 rad, read 8 ms apart would look like 0.19 rad/s: differences of
single samples are no speed). Both for :data:`STILL_S` on end: :attr:`Stillness.still`.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from op2motion.robot.framework import CONTROL_PERIOD_S

GYRO_TAU_S = 0.1            # the gyro's low-pass [s]
STILL_GYRO_RAD_S = 0.1      # the low-passed torso rate below this [rad/s] ...
WINDOW_S = 0.25             # ... and every joint within ...
STILL_JOINT_RAD = 0.02      # ... this [rad] (1.1°) of where it was this long before ...
STILL_S = 0.5               # ... for this long [s]: still


class Stillness:
    """Fed every control tick (:meth:`update`); :attr:`still` once the body has kept still (module docstring)."""

    def __init__(self) -> None:
        self.rate: np.ndarray | None = None
        self.history: deque[np.ndarray] = deque(maxlen=max(1, int(round(WINDOW_S / CONTROL_PERIOD_S))) + 1)
        self.still_ticks = 0

    def update(self, gyro_rad_s: np.ndarray, joints_rad: np.ndarray) -> None:
        """One tick's gyro (3,) [rad/s] and joint angles (n,) [rad]."""
        gyro = np.asarray(gyro_rad_s, dtype=float)
        blend = CONTROL_PERIOD_S / (GYRO_TAU_S + CONTROL_PERIOD_S)
        self.rate = gyro.copy() if self.rate is None else self.rate + blend * (gyro - self.rate)
        self.history.append(np.asarray(joints_rad, dtype=float).copy())
        calm = (len(self.history) == self.history.maxlen and math.hypot(*self.rate.tolist()) < STILL_GYRO_RAD_S
                and float(np.max(np.abs(self.history[-1] - self.history[0]))) < STILL_JOINT_RAD)
        self.still_ticks = self.still_ticks + 1 if calm else 0

    @property
    def still(self) -> bool:
        """Still for :data:`STILL_S` on end."""
        return self.still_ticks * CONTROL_PERIOD_S >= STILL_S - 1e-9
