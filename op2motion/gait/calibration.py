"""How stiff are this robot's servos? Measured while it stands, before the first step.

The plan leads every goal by the servo model's feed-forward ``f`` (the planned joint torque over the model's Kp):
with servos of the model's stiffness a joint sags by exactly ``f`` and lands on its planned angle. A servo ``s``
times as stiff sags by ``f / s``. While the robot stands at the start of a walk (quasi-static, the plan's standing
and weight-shift rows), :class:`StiffnessCalibration` fits ``1 / s`` by least squares over the leg joints from what
they sag, the plan's goal less the angle measured, against their feed-forward (the legs' sag trims, which start from
zero, take a part of the sag out meanwhile: the fit measures what the feed-forward still has to add), and then

* gives back, before the first step, what a softer servo needs on top of the plan's feed-forward (``f (1/s - 1)``,
  ramped in over :data:`RAMP_S`; nothing is taken from a stiffer one: less feed-forward made the stiff members of the
  robustness family turn and drift);
* says how soft the servos are (:attr:`softness`, 0 at the model's stiffness, 1 at :data:`SOFT_STIFFNESS` or
  softer) for the controller's gain schedule (:attr:`~.feedback.Feedback.soft_kp`).

A heavier body than modelled sags more too, and is measured as softer servos: the same compensation fits it. In the
robustness family (MuJoCo and PyBullet alike) the estimate reads 0.97 for the model's servos, 0.68 for servos at 0.6
of its stiffness, 1.28 at 1.6, 0.60 and 1.39 in the corners where the torso is heavier or lighter.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from op2motion.gait.generator import Gait
from op2motion.robot.framework import CONTROL_PERIOD_S

SETTLE_S = 0.25             # standing this long before the first sample: the servos have settled under the load
RAMP_S = 0.3                # the calibration ends this long before the first step; the compensation ramps in meanwhile
SOFT_STIFFNESS = 0.6        # an estimate this low (or lower) counts as fully soft (softness 1)
MIN_FEED_FORWARD_RAD2 = 1e-8  # below this summed squared feed-forward there is nothing to fit (a plan without load)


@dataclass
class StiffnessCalibration(ABC):
    """The servos' stiffness relative to the model, from the standing rows before the first step; the feed-forward
    of a row is the kind of walk's (:meth:`_ff`: :class:`PlannedCalibration` from a whole plan,
    :class:`~.steer_feedback.RollingCalibration` from the rows as they are planned).

    Attributes:
        index: the calibrated joints (n,) (indices into the servos).
        start_row, end_row: the walk rows sampled (before the first step).
        first_step: the walk row the first step starts.
        sums: the least-squares sums (feed-forward · sag, feed-forward²) [rad²].
    """

    index: np.ndarray
    start_row: int
    end_row: int
    first_step: int
    sums: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def reset(self) -> None:
        """Forget the samples."""
        self.sums = np.zeros(2)

    @abstractmethod
    def _ff(self, k: int) -> np.ndarray | None:
        """The feed-forward (n,) [rad] of the calibrated joints at walk row ``k`` (None where there is none)."""

    def observe(self, k: int, goals: np.ndarray, measured: np.ndarray) -> None:
        """Gait row ``k``'s goals sent and joint angles measured (20,) [rad]: a sample while standing."""
        ff = self._ff(k) if self.start_row <= k < self.end_row else None
        if ff is not None:
            sag = (goals - measured)[self.index]
            self.sums += np.array([float(ff @ sag), float(ff @ ff)])

    @property
    def estimate(self) -> float:
        """The servos' stiffness over the model's [1] (1 until there is something to fit)."""
        along, norm = self.sums
        if norm < MIN_FEED_FORWARD_RAD2 or along <= 0.0:
            return 1.0
        return float(norm / along)

    @property
    def softness(self) -> float:
        """0 at the model's stiffness or stiffer, 1 at :data:`SOFT_STIFFNESS` or softer, linear between."""
        return min(max((1.0 - self.estimate) / (1.0 - SOFT_STIFFNESS), 0.0), 1.0)   # np.clip: microseconds a float

    def compensation(self, k: int, size: int) -> np.ndarray:
        """The goals' change (size,) [rad] at gait row ``k``: the feed-forward a softer servo lacks, ramped in
        between the end of the calibration and the first step (zero before)."""
        out = np.zeros(size)
        ramp = self.first_step - self.end_row
        weight = 1.0 if ramp <= 0 else min(max((k - self.end_row) / ramp, 0.0), 1.0)
        lack = max(1.0 / self.estimate - 1.0, 0.0)
        ff = self._ff(k) if weight and lack else None
        if ff is not None:
            out[self.index] = weight * lack * ff
        return out


@dataclass(kw_only=True)
class PlannedCalibration(StiffnessCalibration):
    """The :class:`StiffnessCalibration` of a planned gait; ``feed_forward``: per gait row (K, n), the plan's servo
    feed-forward of the calibrated joints [rad]."""

    feed_forward: np.ndarray

    @classmethod
    def of(cls, gait: Gait, index: np.ndarray) -> "PlannedCalibration":
        """The calibration of ``gait`` over the servos ``index`` (the legs)."""
        first = int(np.argmax(gait.timeline.step >= 0)) if np.any(gait.timeline.step >= 0) else len(gait.joints)
        end = first - int(round(RAMP_S / CONTROL_PERIOD_S))
        start = int(round(SETTLE_S / CONTROL_PERIOD_S))
        return cls(np.asarray(index, dtype=int), start, max(start, end), first,
                   feed_forward=(gait.goals - gait.joints)[:, index])

    def _ff(self, k: int) -> np.ndarray | None:
        return self.feed_forward[k] if 0 <= k < len(self.feed_forward) else None
