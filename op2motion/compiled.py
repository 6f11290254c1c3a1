"""Compiled kernels that one process at a time compiles: the others wait for it and load what it cached.

numba compiles a kernel at its first call and keeps the machine code on disk (``cache=True``). Processes that start
together on a fresh install or checkout (a library build's workers, a test run's processes) would each compile the
same kernel: seconds of CPU each (the PSO's loop about 9 s, the whole-body IK's 4 s on one core), all of them
at once. :class:`CompileOnce` wraps a kernel so that its first call in each process runs under a lock file named
after the kernel: the first process compiles and writes the cache, the others wait and then load it (a few tenths
of a second). Later calls go straight to the kernel. Where no lock file can be made (a read-only temp folder), the
first call runs unlocked, as before.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import tempfile
import threading
from pathlib import Path
from typing import Any, Generic, Iterator, TypeVar, cast

R = TypeVar("R")


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
        with self._guard, _held(lock_path(self.kernel)):
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
    """An exclusive ``flock`` on ``path`` while inside; nothing when the file cannot be opened."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)          # closing the last descriptor releases the lock
