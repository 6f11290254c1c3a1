"""Worker processes that end with their parent, however it ends, and run their maths on one thread each.

Shared by the pose-library builds (:mod:`op2motion.library.build`) and the gait tuning (:mod:`op2motion.tune`):
:func:`worker_init` makes a pool's worker ignore Ctrl-C (the parent decides) and die with its parent (Linux
``PR_SET_PDEATHSIG``, and a watchdog thread that polls the parent's pid elsewhere); :func:`one_thread_each` starts
workers whose BLAS and numba use one thread (the workers fill the cores already: threads spinning against other
processes made a library target take eight times as long); :func:`starting_workers` ignores Ctrl-C and holds SIGTERM
while workers start, so that an interrupt never cuts a worker's start-up message in half.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import threading
import time
from typing import Iterator, Literal, get_args

from op2motion.processes.interrupts import signals_held

#: Where a pool's work runs: local worker processes, or a Ray cluster.
ExecutorName = Literal["process", "ray"]
EXECUTORS: tuple[ExecutorName, ...] = get_args(ExecutorName)
WATCHDOG_PERIOD_S = 0.5
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")
_PR_SET_PDEATHSIG = 1   # linux/prctl.h


def _watch_parent(parent: int) -> None:
    while True:
        if os.getppid() != parent:
            os._exit(1)
        time.sleep(WATCHDOG_PERIOD_S)


def worker_init(parent: int) -> None:
    """In each worker: ignore Ctrl-C (the parent decides) and die with the parent (pid ``parent``)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent:   # the parent died before the death signal was armed
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()


@contextlib.contextmanager
def one_thread_each() -> Iterator[None]:
    """Workers started in here run their maths libraries on one thread each (see the module docstring)."""
    saved = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    os.environ.update({name: "1" for name in THREAD_VARIABLES})
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@contextlib.contextmanager
def starting_workers() -> Iterator[None]:
    """Start worker processes in here: Ctrl-C is ignored (the workers start with it ignored, :func:`worker_init`
    keeps it so) and a SIGTERM is held until the block ends, then delivered (:func:`op2motion.processes.interrupts.
    signals_held`). A signal acted on while a spawned worker starts would leave it reading half a start-up message,
    and it would print a traceback as the command ends."""
    with signals_held(ignore_ctrl_c=True):
        yield
