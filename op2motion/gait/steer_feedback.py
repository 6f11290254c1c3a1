"""The walk controller's feedback for a walk planned while it walks: the same learner, odometry and calibration,
fed from the rows as the rolling planner writes them (:mod:`.rolling`), not from a whole plan.

* :class:`RollingLearner` (:mod:`.learning`): a step learns, and uses what was learnt, when its swing is like the
  last one of the same side (a planned walk also compares with the next; a steered one cannot see it). When the
  command changes the steps' shape, that side's memory is forgotten: it belonged to another step.
* :class:`RollingOdometry` (:mod:`.odometry`): each landing is measured where the rows say it happens; a landing that
  closes the feet keeps its miss, and the controller holds that foot where it landed until it swings again (its next
  swing carries it from there to its planned place).
* :class:`RollingCalibration` (:mod:`.calibration`): the servos' stiffness measured over the first standing rows of
  the walk (the planner lets no step begin before the compensation is in).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from op2motion.gait.calibration import RAMP_S, SETTLE_S, StiffnessCalibration
from op2motion.gait.learning import SHAPE_TOL_M, SHAPE_TOL_RAD, StepLearner
from op2motion.gait.odometry import FootOdometry
from op2motion.gait.rows import RowBuffer
from op2motion.kinematics.leg_ik import Leg
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.support import Side


@dataclass(kw_only=True)
class RollingLearner(StepLearner):
    """A :class:`~.learning.StepLearner` over rolling rows (see the module docstring)."""

    source: RowBuffer
    alike_of: dict[int, bool] = field(default_factory=dict)
    last_shape: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def rolling(cls, source: RowBuffer, rows_per_step: int, joints: Mapping[str, np.ndarray], size: int,
                gain: float, shift: int) -> "RollingLearner":
        """The learner of a rolling walk whose steps are ``rows_per_step`` rows long."""
        return cls(rows_per_step, {side: np.asarray(index, dtype=int) for side, index in joints.items()}, size, gain,
                   shift, source=source)

    def reset(self) -> None:
        """Forget everything learned, and the steps' shapes."""
        super().reset()
        self.alike_of, self.last_shape = {}, {}

    def _where(self, k: int) -> tuple[Side, int] | None:
        if not self.source.has(k):
            return None
        learn = self.source.obj("learn", k)
        if learn is None:
            return None
        side, r, shape, step = learn
        if step not in self.alike_of:
            before = self.last_shape.get(side)
            diff = None if before is None else np.abs(shape - before)
            alike = diff is not None and bool(np.all(diff[:4] <= SHAPE_TOL_M) and np.all(diff[4:] <= SHAPE_TOL_RAD))
            self.alike_of[step], self.last_shape[side] = alike, shape
            if not alike:
                self.memory[side][:] = 0.0
                self._pending[side][:] = 0.0
            for old in [s for s in self.alike_of if s < step - 4]:
                del self.alike_of[old]
        return (side, r) if r < self.rows and self.alike_of[step] else None


@dataclass(kw_only=True)
class RollingOdometry(FootOdometry):
    """A :class:`~.odometry.FootOdometry` over rolling rows (see the module docstring)."""

    source: RowBuffer
    after: int
    due: dict[int, tuple[Side, Side, bool]] = field(default_factory=dict)

    @classmethod
    def rolling(cls, source: RowBuffer, legs: Mapping[str, Leg], after: int) -> "RollingOdometry":
        """The odometry of a rolling walk, each landing measured ``after`` rows into its double support."""
        return cls(dict(legs), source=source, after=after)

    def reset(self) -> None:
        """Forget the measurements."""
        super().reset()
        self.due = {}

    def observe(self, k: int, measured: np.ndarray) -> None:
        """Row ``k``'s joint angles (20,) [rad]: note a landing that begins here; measure one that is due."""
        if not self.source.has(k):
            return
        landing = self.source.obj("landing", k)
        if landing is not None:
            stance, landed, closing, rows = landing
            self.due[k + min(self.after, rows - 1)] = (stance, landed, closing)
            if self.last is not None and self.last[0] == landed:
                self.last = None                  # the foot held where it closed the feet has stepped since
        if k in self.due:
            stance, landed, closing = self.due.pop(k)
            self._landing(measured, stance, landed, self.source.feet(stance, k), self.source.feet(landed, k), closing)


@dataclass(kw_only=True)
class RollingCalibration(StiffnessCalibration):
    """A :class:`~.calibration.StiffnessCalibration` over rolling rows (see the module docstring)."""

    source: RowBuffer

    @classmethod
    def rolling(cls, source: RowBuffer, index: np.ndarray, first_step_row: int) -> "RollingCalibration":
        """The calibration over the standing rows before ``first_step_row`` (the first step's earliest row)."""
        start = int(round(SETTLE_S / CONTROL_PERIOD_S))
        end = max(start, first_step_row - int(round(RAMP_S / CONTROL_PERIOD_S)))
        return cls(np.asarray(index, dtype=int), start, end, first_step_row, source=source)

    def _ff(self, k: int) -> np.ndarray | None:
        if not self.source.has(k):
            return None
        ff: np.ndarray = (self.source.get("goals", k) - self.source.get("joints", k))[self.index]
        return ff
