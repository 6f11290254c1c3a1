"""How a run of the 8 ms loop ends (:mod:`.loop`): by its plan's end, by a fault (:mod:`.safety`'s policy) or by a
stop request (Ctrl-C). A controller that stops itself (``stops_itself``: a walk, planned or steered, closes its feet
and stands) is told to stop and runs on until it is done, at most :data:`SOFT_STOP_MAX_S`. Otherwise a stop freezes
the goals at a row and holds them :data:`STOP_HOLD_S` before the loop ends: a walk's plan played open loop at its
next row on both feet (:func:`stop_row`), anything else the row it is at; a fall lowers the torque limits and,
:data:`~.safety.FALL_SETTLE_S` later, relaxes the goals to where the joints lie.
"""

from __future__ import annotations

from typing import Any, Callable

from op2motion.bus import safety
from op2motion.bus.robot import OP2
from op2motion.bus.tables import CM730_ID
from op2motion.robot.controller import hooks_of
from op2motion.robot.support import Support

STOP_HOLD_S = 0.3                  # after a stop, the held goals are sent this long before the loop ends
SOFT_STOP_MAX_S = 2.0              # a controller that stops itself gets this long to be done (a walk: up to two steps
                                   # and standing: about 1.5 s, docs/robot.md); then its goals freeze where they are


def stop_row(plan: Any, row: int) -> int:
    """Where a stop request at plan row ``row`` freezes the goals: a walk's next row on both feet (one row into
    its double support when it lasts that long); any other plan the row it is at."""
    contacts = plan.contacts if plan.contact is not None else None
    if contacts is None:
        return row
    for r in range(row, len(contacts)):
        if contacts[r] is Support.DOUBLE:
            nxt = min(r + 1, len(contacts) - 1)
            return nxt if contacts[nxt] is Support.DOUBLE else r
    return row


class Stops:
    """How a run ends: the row a stop froze the goals at, when the loop ends after holding them, a fall's settling."""

    def __init__(self) -> None:
        self.frozen_at: int | None = None
        self.end_at: float | None = None
        self.fall_until: float | None = None
        self.soft_until: float | None = None

    def fault(self, fault: safety.Fault, robot: OP2, plan: Any, row: int, k: int, now: float) -> None:
        """React to the run's first fault (:mod:`.safety`'s policy)."""
        if fault.kind == "fell":
            robot.torque_limit(safety.FALL_TORQUE_LIMIT)
            self.frozen_at, self.fall_until = row, now + safety.FALL_SETTLE_S
        elif fault.kind == "not answering" and fault.id == CM730_ID:
            self.frozen_at = row
        else:
            self.frozen_at = stop_row(plan, row) if k else 0

    def request(self, plan: Any, row: int, k: int, controller: Any = None, now: float = 0.0) -> None:
        """A stop request (Ctrl-C): a controller that stops itself is told to; a walk's plan played open loop
        freezes on its next double support, anything else at once."""
        if self.frozen_at is not None or self.soft_until is not None:
            return
        hooks = hooks_of(controller)
        if k and hooks.stops_itself:
            hooks.stop()
            self.soft_until = now + SOFT_STOP_MAX_S
        else:
            self.frozen_at = stop_row(plan, row) if k else 0

    def soft_over(self, row: int, now: float) -> None:
        """A controller told to stop that is not done in time: its goals freeze where they are."""
        if self.soft_until is not None and self.frozen_at is None and now >= self.soft_until:
            self.frozen_at = row

    def frozen(self, row: int, now: float) -> bool:
        """Whether the goals are frozen at ``row`` (the hold's end is timed from the first frozen tick)."""
        if self.frozen_at is None or row < self.frozen_at:
            return False
        if self.end_at is None:
            self.end_at = now + STOP_HOLD_S
        return True

    def over(self, now: float, t: float, duration: float, done: Callable[[], bool], until_done: bool) -> bool:
        """Whether the loop ends after this tick (``done``: whether the controller is done)."""
        if self.frozen_at is None:
            if self.soft_until is not None:
                return done()
            return t >= duration or (until_done and done())
        return self.end_at is not None and now >= self.end_at and self.fall_until is None
