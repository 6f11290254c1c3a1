"""Where a study's trials run: worker processes on this machine, or Ray tasks (this machine or a cluster).

Both keep ``workers`` trials in flight and hand back each finished one as it comes: :class:`ProcessTrials` runs a
pool of spawned processes that die with their parent and use one maths thread each (:mod:`op2motion.processes.workers`);
:class:`RayTrials` runs Ray tasks in a :func:`op2motion.library.cluster.ray_session` (Ray's output off the
terminal, Ctrl-C and SIGTERM noted between Ray's calls, no Ray process left behind). The function run must be a
module-level function with picklable arguments.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
from typing import Any, Callable, Iterator, Protocol

from op2motion.processes.workers import ExecutorName

WAIT_S = 0.25                 # the driver waits this long at a time, so signals are handled between waits [s]


class TrialRunner(Protocol):
    """Runs ``fn(*args)`` for trial numbers, ``workers`` at a time."""

    workers: int

    def submit(self, number: int, fn: Callable[..., Any], *args: Any) -> None:
        """Start trial ``number``."""

    def finished(self) -> list[tuple[int, Any]]:
        """The trials that finished since the last call, as (number, result); waits at most :data:`WAIT_S`."""

    @property
    def running(self) -> int:
        """Trials in flight."""


class ProcessTrials:
    """Trials in a pool of worker processes (see the module docstring)."""

    def __init__(self, workers: int):
        from op2motion.processes.workers import worker_init

        self.workers = workers
        self._pool = cf.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                            initializer=worker_init, initargs=(os.getpid(),))
        self._futures: dict[cf.Future[Any], int] = {}

    def submit(self, number: int, fn: Callable[..., Any], *args: Any) -> None:
        from op2motion.processes.workers import one_thread_each, starting_workers

        with one_thread_each(), starting_workers():      # a spawning pool starts its workers as trials come
            self._futures[self._pool.submit(fn, *args)] = number

    def finished(self) -> list[tuple[int, Any]]:
        if not self._futures:
            return []
        done, _ = cf.wait(list(self._futures), timeout=WAIT_S, return_when=cf.FIRST_COMPLETED)
        return [(self._futures.pop(f), f.result()) for f in done]

    @property
    def running(self) -> int:
        return len(self._futures)

    def close(self) -> None:
        """Cancel what has not started, end the workers at once."""
        for future in self._futures:
            future.cancel()
        for process in list(getattr(self._pool, "_processes", {}).values()):
            with contextlib.suppress(Exception):
                process.kill()
        self._pool.shutdown(wait=True, cancel_futures=True)


class RayTrials:
    """Trials as Ray tasks (see the module docstring)."""

    def __init__(self, ray: Any, stop: Any, workers: int):
        self.workers, self._ray, self._stop = workers, ray, stop
        self._refs: dict[Any, int] = {}
        self._remote: dict[Callable[..., Any], Any] = {}

    def submit(self, number: int, fn: Callable[..., Any], *args: Any) -> None:
        if fn not in self._remote:
            self._remote[fn] = self._ray.remote(num_cpus=1)(fn)
        self._refs[self._remote[fn].remote(*args)] = number

    def finished(self) -> list[tuple[int, Any]]:
        self._stop.check()
        if not self._refs:
            return []
        done, _ = self._ray.wait(list(self._refs), num_returns=1, timeout=WAIT_S)
        return [(self._refs.pop(ref), self._ray.get(ref)) for ref in done]

    @property
    def running(self) -> int:
        return len(self._refs)

    def close(self) -> None:
        for ref in self._refs:
            with contextlib.suppress(Exception):
                self._ray.cancel(ref, force=True)


def check_executor(kind: ExecutorName, address: str | None) -> None:
    """Before anything is written: an ``address`` only for Ray; for Ray, the address a running Ray head
    (:func:`~op2motion.library.cluster.check_address`: a closed port, a host that does not answer or a server that
    is not Ray is bad input; checked first, it needs no Ray) and Ray installed."""
    from op2motion.errors import InputError, ref

    if kind != "ray":
        if address is not None:
            raise InputError(f"expected {ref('address')} only with {ref('executor')} ray", "address")
        return
    from op2motion.library.cluster import check_address, check_ray

    if address is not None:
        check_address(address)
    check_ray(None)


@contextlib.contextmanager
def trials_on(kind: ExecutorName, workers: int, address: str | None = None) -> Iterator[ProcessTrials | RayTrials]:
    """A :class:`TrialRunner` on ``kind`` ``process`` (a pool of ``workers``) or ``ray`` (``address``: a cluster;
    None: Ray on this machine with ``workers`` CPUs), closed however the study ends."""
    if kind == "ray":
        from op2motion.library.cluster import ray_session

        with ray_session(address, workers) as (ray, stop):
            trials = RayTrials(ray, stop, workers)
            try:
                yield trials
            finally:
                trials.close()
        return
    pool = ProcessTrials(workers)
    try:
        yield pool
    finally:
        pool.close()
