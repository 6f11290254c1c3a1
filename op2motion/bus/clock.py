"""The one clock the bus keeps its time by: the port's reads and writes, the client's waits for replies, the robot's
pauses and the 8 ms loop all ask it, never :mod:`time` directly.

* :class:`RealClock`: the wall (``time.monotonic``, ``time.sleep``), for a real robot and for an emulated one on a
  pseudo-terminal.
* :class:`LockstepClock`: simulated time that moves only when someone waits. ``sleep_until(t)`` runs every
  listener (an emulated OP2: its wire, its devices and its physics) up to ``t`` and then sets the time to ``t``, so
  the client, the wire and the body advance together, deterministically, as fast as the machine computes them
  (a 12 s walk in a few seconds), and two runs of the same program give the same rows. Work done between two waits
  takes no simulated time: a program checked in lockstep is checked for what it sends and when it asks, not for how
  long its Python takes (the real-time mode and ``op2motion bench`` measure that).
"""

from __future__ import annotations

import time
from typing import Callable, Protocol


class Clock(Protocol):
    """What the bus needs of a clock: the time [s] on a monotonic scale and a wait until a time."""

    def now(self) -> float:
        """The time [s] (monotonic; its zero means nothing)."""
        ...

    def sleep_until(self, t: float) -> None:
        """Return at time ``t`` [s] (at once if it has passed)."""
        ...


class RealClock:
    """The wall clock (see the module docstring)."""

    def now(self) -> float:
        """``time.monotonic()`` [s]."""
        return time.monotonic()

    def sleep_until(self, t: float) -> None:
        """Sleep until the monotonic time ``t`` [s]."""
        left = t - time.monotonic()
        if left > 0.0:
            time.sleep(left)


#: The clock of every real port (one instance: it keeps no state).
REAL = RealClock()


def sleep(clock: Clock, seconds: float) -> None:
    """Wait ``seconds`` [s] on ``clock``."""
    clock.sleep_until(clock.now() + max(seconds, 0.0))


class LockstepClock:
    """Simulated time advanced by the waits (see the module docstring). ``start_s`` is its first reading [s];
    ``pace`` (None: as fast as it computes) holds it to that many simulated seconds a wall second at most, for a
    person or a program that acts by the wall clock (the studio following an edit)."""

    def __init__(self, start_s: float = 0.0, pace: float | None = None):
        self._now = float(start_s)
        self._listeners: list[Callable[[float], None]] = []
        self.pace = pace
        self._wall0, self._sim0 = time.monotonic(), float(start_s)

    def listen(self, advance: Callable[[float], None]) -> None:
        """Have ``advance(t)`` run before the time moves to ``t`` (an emulated robot stepping up to it)."""
        self._listeners.append(advance)

    def now(self) -> float:
        """The simulated time [s]."""
        return self._now

    def sleep_until(self, t: float) -> None:
        """Run the listeners up to ``t`` [s], then set the time to it (never backwards)."""
        if t <= self._now:
            return
        for advance in self._listeners:
            advance(t)
        self._now = t
        if self.pace:
            left = self._wall0 + (t - self._sim0) / self.pace - time.monotonic()
            if left > 0.0:
                time.sleep(left)
