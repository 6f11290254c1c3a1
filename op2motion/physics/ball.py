"""A ball on the floor for a kick's physics check: where it lies, what it is, and what the kick did to it.

The ball is a size-1 football (:data:`BALL_RADIUS_M`, :data:`BALL_MASS_KG`; the RoboCup kid-size leagues have played
size-1 balls), a free sphere on the same floor as the robot, placed at rest at (``x_m``, ``y_m``) in the world frame
(the floor; the run's start with its flat sole at the origin: X forward, Y left). Its contacts with the robot and the
floor are the engine's to resolve; they are not the robot's (the judge never sees them: a kicking foot on the ball is
not a foot on the floor, and a ball on the floor is not a fall). :class:`BallWatch` reads its velocity every control
period (8 ms) of the run; :class:`BallReport` gives the kick's result: the ball's fastest speed and the direction it
went then, when the robot first moved it, and how far it had rolled by the run's end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from op2motion.errors import InputError

#: A size-1 football: 46-51 cm around by the makers' figures; 0.48 m around [m].
BALL_RADIUS_M = 0.48 / (2.0 * math.pi)
#: ... and 180-250 g by the makers' figures [kg].
BALL_MASS_KG = 0.2
MOVED_M_S = 0.05            # the ball counts as moved once it is this fast [m/s] (it lies still to within mm/s)
MAX_PLACE_M = 2.0           # the ball lies within this of the start [m]


@dataclass(frozen=True)
class Ball:
    """A ball at rest on the floor at (``x_m``, ``y_m``) [m] (world frame), of ``radius_m`` [m] and ``mass_kg``
    [kg]."""

    x_m: float
    y_m: float
    radius_m: float = BALL_RADIUS_M
    mass_kg: float = BALL_MASS_KG

    def __post_init__(self) -> None:
        for name, value in (("x_m", self.x_m), ("y_m", self.y_m)):
            if not (math.isfinite(value) and abs(value) <= MAX_PLACE_M):
                raise InputError(f"expected the ball within {MAX_PLACE_M:g} m of the start, got {name} = {value!r}",
                                 "ball")
        if not (0.02 <= self.radius_m <= 0.2 and 0.01 <= self.mass_kg <= 2.0):
            raise InputError(f"expected a ball of 2-20 cm radius and 10 g-2 kg, got {self.radius_m:g} m and "
                             f"{self.mass_kg:g} kg", "ball")

    @property
    def inertia_kg_m2(self) -> float:
        """Its moment of inertia about any axis through its centre [kg·m²]: a thin shell's, 2/3 m r² (a football is
        a skin filled with air)."""
        return 2.0 / 3.0 * self.mass_kg * self.radius_m ** 2

    @property
    def centre(self) -> np.ndarray:
        """Where its centre starts (3,) [m]: on the floor."""
        return np.array([self.x_m, self.y_m, self.radius_m])


class BallEngine(Protocol):
    """What :class:`BallWatch` reads of an engine."""

    def ball_state(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The ball's centre (3,) [m] and velocity (3,) [m/s], world frame (None: no ball)."""
        ...


@dataclass(frozen=True)
class BallReport:
    """What a run did to the ball: its fastest speed [m/s] (horizontal) and the direction it rolled then [deg] (0:
    +X, forward; 90: +Y, left), when it first moved [s] (None: it never did), and how far it was from where it lay
    at the run's end [m]."""

    max_speed_mps: float
    direction_deg: float
    moved_at_s: float | None
    travelled_m: float

    def describe(self) -> str:
        """In words, for the run's lines."""
        if self.moved_at_s is None:
            return "ball: not touched"
        return (f"ball: {self.max_speed_mps:.2f} m/s towards {self.direction_deg:+.0f}° (moved at "
                f"{self.moved_at_s:.2f} s), {self.travelled_m:.2f} m away by the end")


class BallWatch:
    """The ball's velocity read every control period of a run (see the module docstring)."""

    def __init__(self, engine: BallEngine, ball: Ball):
        self.engine, self.ball = engine, ball
        self.times: list[float] = []
        self.velocities: list[np.ndarray] = []
        self.last = ball.centre

    def sample(self, t_s: float) -> None:
        """Read the ball at simulated time ``t_s`` [s]."""
        state = self.engine.ball_state()
        if state is not None:
            self.last, velocity = state
            self.times.append(t_s)
            self.velocities.append(velocity)

    def report(self) -> BallReport:
        """The run's :class:`BallReport`."""
        if not self.velocities:
            return BallReport(0.0, 0.0, None, 0.0)
        v = np.array(self.velocities)[:, :2]
        speed = np.hypot(v[:, 0], v[:, 1])
        fastest = int(np.argmax(speed))
        moved = np.flatnonzero(speed >= MOVED_M_S)
        return BallReport(float(speed[fastest]), math.degrees(math.atan2(v[fastest, 1], v[fastest, 0])),
                          float(self.times[int(moved[0])]) if moved.size else None,
                          float(np.hypot(*(self.last[:2] - self.ball.centre[:2]))))
