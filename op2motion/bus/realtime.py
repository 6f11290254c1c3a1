"""Real-time scheduling for the threads that keep the bus's time, where the system allows it.

The ROBOTIS framework runs its 8 ms motion timer in a thread at ``SCHED_RR`` priority 31
(``Linux/build/LinuxMotionTimer.cpp``), so that the loop keeps its period on a busy PC. :func:`realtime` does the
same for the calling thread for the length of a ``with`` block (the loop: :data:`LOOP_PRIORITY`; the emulated
OP2's serving thread, which stands in for the robot's own firmware, one step below: :data:`EMULATOR_PRIORITY`) and
puts the thread back as it was afterwards. Without the privilege (not root, no ``CAP_SYS_NICE``, not Linux) the
thread runs as it is and the block learns so. Both threads sleep most of each period, so they cannot starve the
system.

:func:`steady` keeps Python's garbage collector from pausing such a thread for long: a full collection walks every
object the process holds (the physics engines, the planners: 10–20 ms here, more on a loaded machine, longer than
five 8 ms ticks); inside the block it walks only what was made since the block began.
"""

from __future__ import annotations

import contextlib
import gc
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


@contextlib.contextmanager
def steady() -> Iterator[None]:
    """Collect now and freeze what exists (:func:`gc.freeze`), so that the collections inside the block are short;
    unfreeze after it."""
    gc.collect()
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()
