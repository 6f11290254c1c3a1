"""Compiled kernels that one process at a time compiles: the others wait for it and load what it cached.

numba compiles a kernel at its first call and keeps the machine code on disk (``cache=True``). Processes that start
together on a fresh install or checkout (a library build's workers, a test run's processes) would each compile the
same kernel: seconds of CPU each (the PSO's loop about 9 s, the whole-body IK's 4 s on one core), all of them
at once. :class:`CompileOnce` wraps a kernel so that its first call in each process runs under a lock file named
after the kernel: the first process compiles and writes the cache, the others wait and then load it (a few tenths
of a second). Later calls go straight to the kernel. Where no lock file can be made (a read-only temp folder, a
symbolic link planted in its place), or the lock stays taken for :data:`WAIT_S` (a process stopped mid-compile with
Ctrl-Z, another user's process holding it), the first call runs unlocked, as before: a lock never stops a command.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Generic, Iterator, TypeVar, cast

R = TypeVar("R")
WAIT_S = 120.0          # the longest wait for another process's compile (the PSO loop's takes 9 s on one core) [s]
POLL_S = 0.05           # how often a waiting process tries the lock [s]


class CompileOnce(Generic[R]):
    """A numba kernel (a ``njit(cache=True)`` dispatcher) whose first call in this process holds the machine-wide
    lock of that kernel (:func:`lock_path`); call it as the kernel itself."""

    def __init__(self, kernel: Any):
        self.kernel = kernel
        self._ready = False
        self._guard = threading.Lock()

    def __call__(self, *args: Any) -> R:
        if self._ready:
            return cast(R, self.kernel(*args))
        from op2motion.processes.imports import scipy_blas_for_numba

        with self._guard, _held(lock_path(self.kernel)), scipy_blas_for_numba():
            result = cast(R, self.kernel(*args))
            self._ready = True
        return result


def lock_path(kernel: Any) -> Path:
    """The lock file of ``kernel`` in the temp folder, named by its source file and name (two copies of the package,
    two locks: numba caches each copy's kernels beside its own sources)."""
    function = getattr(kernel, "py_func", kernel)
    key = f"{function.__code__.co_filename}:{function.__qualname__}".encode()
    return Path(tempfile.gettempdir()) / f"op2motion-compile-{hashlib.sha256(key).hexdigest()[:16]}.lock"


@contextlib.contextmanager
def _held(path: Path) -> Iterator[None]:
    """An exclusive ``flock`` on ``path`` while inside, waited for at most :data:`WAIT_S`; nothing when the file
    cannot be opened (never through a symbolic link) or the wait runs out."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o666)
    except OSError:
        yield
        return
    try:
        deadline = time.monotonic() + WAIT_S
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    break
                time.sleep(POLL_S)
        yield
    finally:
        os.close(fd)          # closing the last descriptor releases the lock (if it was taken)
