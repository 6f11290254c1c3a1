"""Learning the servos from step to step: a repetitive (iterative learning) feed-forward for the legs.

A walk repeats itself: every left step asks the legs for nearly the same angles as the left step before it. What
the servos fail to follow in one step (they sag under load, lag behind a fast swing, or overshoot when stiffer than
the servo model assumed) they fail to follow the same way in the next. :class:`StepLearner` keeps, per swing side
and per row of a step, a correction of the swing leg's goals (R, 20) [rad] and after each measurement adds to it
``gain`` times what the swing leg's joints missed, ``shift`` rows earlier (a goal shows in the joints a few ticks
later: servo lag and sensor latency). The next step of the same side starts from there: after a few steps the swing
foot follows its path whatever the servos' stiffness, which the plan cannot know, and lands where planned. Only the
swing leg learns: the stance leg's misses are the balance feedback's business (learning them too fought it in the
robustness family). ``forget`` and a short moving average keep noise and one-off events (a slip, a push) from
accumulating.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from op2motion.gait.generator import Gait
from op2motion.robot.support import Side

MAX_LEARNED_RAD = 0.15             # a learned correction stays within this per joint and row [rad] (8.6°)
SHAPE_TOL_M = 0.005                # two steps whose swing starts and ends this close (stance frame) are alike
SHAPE_TOL_RAD = 0.035              # ... and turn this alike (2°)
SMOOTH_ROWS = 3                    # the moving average across rows that keeps the correction smooth


@dataclass
class StepLearner(ABC):
    """Per swing side, the learned correction of each row of a step (see the module docstring); where a row lies in
    a step, and whether that step learns, is the kind of walk's (:meth:`_where`: :class:`PlannedLearner` from a
    whole plan, :class:`~.steer_feedback.RollingLearner` from the rows as they are planned).

    Attributes:
        rows: rows in one step (single support and the double support after it).
        joints: per side, the indices (into the servos) of that leg's joints.
        size: the number of servos.
        gain: share of a miss added to the correction each step.
        shift: rows between a goal and the measurement it shows in.
        forget: share of the correction kept from one step of a side to the next.
    """

    rows: int
    joints: dict[str, np.ndarray]
    size: int
    gain: float
    shift: int
    forget: float = 0.98
    memory: dict[str, np.ndarray] = field(default_factory=dict)
    _pending: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Forget everything learned."""
        self.memory = {side: np.zeros((self.rows, self.size)) for side in self.joints}
        self._pending = {side: np.zeros((self.rows, self.size)) for side in self.joints}

    @abstractmethod
    def _where(self, k: int) -> tuple[Side, int] | None:
        """(swing side, row in the step) of walk row ``k`` when that step learns, else None."""

    def correction(self, k: int) -> np.ndarray:
        """The learned change (size,) [rad] of the goals of gait row ``k`` (zero outside the steps). Call it once
        per row, in order: the last row of a step folds in what that step taught."""
        where = self._where(k)
        if where is None:
            return np.zeros(self.size)
        side, r = where
        out: np.ndarray = self.memory[side][r].copy()
        if r == self.rows - 1:
            self._commit(side)
        return out

    def learn(self, k: int, miss: np.ndarray) -> None:
        """Record what the joints missed (size,) [rad] (intended less measured) at gait row ``k``: the swing leg's
        part corrects its goals ``shift`` rows earlier in the next step of the same side."""
        where = self._where(k - self.shift)
        if where is not None:
            side, r = where
            index = self.joints[side]
            self._pending[side][r, index] += self.gain * miss[index]

    def _commit(self, side: Side) -> None:
        """At the end of a step, fold what it taught into that side's correction (smoothed, bounded)."""
        kernel = np.ones(SMOOTH_ROWS) / SMOOTH_ROWS
        pending = self._pending[side]
        padded = np.pad(pending, ((SMOOTH_ROWS // 2, SMOOTH_ROWS // 2), (0, 0)), mode="edge")
        smooth = np.stack([np.convolve(padded[:, j], kernel, mode="valid") for j in range(self.size)], axis=1)
        self.memory[side] = np.clip(self.forget * self.memory[side] + smooth, -MAX_LEARNED_RAD, MAX_LEARNED_RAD)
        pending[:] = 0.0


@dataclass(kw_only=True)
class PlannedLearner(StepLearner):
    """The :class:`StepLearner` of a planned gait, which knows every step before the first.

    Attributes:
        step_of_row: per gait row (K,), the step it belongs to (-1 before the first, n after the last).
        first_row: per step (n,), its first gait row.
        alike: per step (n,), whether it swings its foot as the step of the same side before or after it (the
            first and the closing steps do not): only those learn and use what was learnt.
        side_of_step: per step (n,), the swinging side.
    """

    step_of_row: np.ndarray
    first_row: np.ndarray
    alike: np.ndarray
    side_of_step: tuple[Side, ...]

    @classmethod
    def of(cls, gait: Gait, joints: dict[str, np.ndarray], gain: float, shift: int) -> "PlannedLearner":
        """The learner of a planned gait; ``joints`` per side the indices of that leg's servos."""
        step = gait.timeline.step
        n = len(gait.footsteps.steps)
        first = np.array([int(np.argmax(step == s)) for s in range(n)], dtype=int)
        ends = np.append(first, int(np.argmax(step == n))) if n else np.zeros(1, dtype=int)
        rows = max(int(np.min(np.diff(ends))), 1) if n else 1
        return cls(rows, {side: np.asarray(index, dtype=int) for side, index in joints.items()},
                   gait.joints.shape[1], gain, shift, step_of_row=step, first_row=first, alike=_alike(gait),
                   side_of_step=tuple(s.side for s in gait.footsteps.steps))

    def _where(self, k: int) -> tuple[Side, int] | None:
        if not 0 <= k < len(self.step_of_row):
            return None
        s = int(self.step_of_row[k])
        if not 0 <= s < len(self.first_row):
            return None
        r = k - int(self.first_row[s])
        return (self.side_of_step[s], r) if r < self.rows and self.alike[s] else None


def _shape(gait: Gait, k: int) -> np.ndarray:
    """Step ``k``'s swing in its stance foot's frame: start (x, y), end (x, y) [m], start and end yaw [rad]."""
    stand, before = gait.footsteps.stance_before(k)
    goal = gait.footsteps.steps[k]
    c, s = np.cos(stand.yaw), np.sin(stand.yaw)
    to_stance = np.array([[c, s], [-s, c]])
    out = []
    for foot in (before, goal):
        out.extend(to_stance @ (np.array([foot.x, foot.y]) - np.array([stand.x, stand.y])))
    out.extend([before.yaw - stand.yaw, goal.yaw - stand.yaw])
    return np.array(out)


def _alike(gait: Gait) -> np.ndarray:
    """Per step, whether it swings like a step of the same side before or after it (the first and the closing steps
    of a walk do not)."""
    n = len(gait.footsteps.steps)
    shapes = [_shape(gait, k) for k in range(n)]

    def same(a: int, b: int) -> bool:
        if not 0 <= b < n:
            return False
        diff = np.abs(shapes[a] - shapes[b])
        return bool(np.all(diff[:4] <= SHAPE_TOL_M) and np.all(diff[4:] <= SHAPE_TOL_RAD))

    return np.array([same(k, k - 2) or same(k, k + 2) for k in range(n)], dtype=bool)
