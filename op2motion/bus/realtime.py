"""Real-time scheduling for the threads that keep the bus's time, where the system allows it.

The ROBOTIS framework runs its 8 ms motion timer in a thread at ``SCHED_RR`` priority 31
(``Linux/build/LinuxMotionTimer.cpp``), so that the loop keeps its period on a busy PC. :func:`realtime` does the
same for the calling thread for the length of a ``with`` block (the loop: :data:`LOOP_PRIORITY`; the emulated
OP2's serving thread, which stands in for the robot's own firmware, one step below: :data:`EMULATOR_PRIORITY`) and
puts the thread back as it was afterwards. Without the privilege (not root, no ``CAP_SYS_NICE``, not Linux) the
thread runs as it is and the block learns so. Both threads sleep most of each period, so they cannot starve the
system.
"""

from __future__ import annotations

import contextlib
import os
from typing import Iterator

LOOP_PRIORITY = 31                 # the framework's motion timer (SCHED_RR)
EMULATOR_PRIORITY = 30


@contextlib.contextmanager
def realtime(priority: int) -> Iterator[bool]:
    """The calling thread at ``SCHED_RR`` ``priority`` inside the block if allowed; yields whether it is."""
    try:
        policy, param = os.sched_getscheduler(0), os.sched_getparam(0)
        os.sched_setscheduler(0, os.SCHED_RR, os.sched_param(priority))
    except (AttributeError, OSError):
        yield False
        return
    try:
        yield True
    finally:
        with contextlib.suppress(OSError):
            os.sched_setscheduler(0, policy, param)
