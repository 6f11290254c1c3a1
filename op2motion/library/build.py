"""``op2motion library build``: solve a grid of reach targets in worker processes, resumably.

Each target runs the posture workflow (:func:`op2motion.workflow.solve`: the same retries and validation as
``optimize``) in a worker process; the parent is the only writer: it writes each reached pose file (atomically),
then the index (:mod:`.index`). A build run again skips the targets its index holds.

Process hygiene: workers ignore SIGINT (the parent handles Ctrl-C: it cancels the pending targets, ends the
workers, writes a complete index and raises :class:`KeyboardInterrupt`), and end when their parent dies however
it dies (Linux ``PR_SET_PDEATHSIG``, and a watchdog thread that polls the parent's pid elsewhere).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

from op2motion.errors import InputError, Interrupted
from op2motion.jsonout import JsonObject
from op2motion.library.grid import Job
from op2motion.library.index import INDEX_JSON, IndexRow, load_index, reconcile, write_index
from op2motion.library.jobs import BuildSettings, JobRecorder, solve_job
from op2motion.processes.workers import EXECUTORS, ExecutorName, one_thread_each, starting_workers, worker_init
from op2motion.robot.spec import Spec
from op2motion.robot.specfile import spec_text

__all__ = ["BuildSettings", "BuildSummary", "Executor", "build_library", "check_workers"]

MAX_WORKERS = 64


@dataclass(frozen=True)
class Executor:
    """Where the targets are solved: ``process`` (a pool on this machine) or ``ray`` (tasks on Ray: ``address`` of
    a running cluster, or None to start Ray here)."""

    kind: ExecutorName = "process"
    address: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in EXECUTORS:
            raise InputError(f"expected process or ray, got {self.kind!r}", "executor")
        if self.address is not None and self.kind != "ray":
            raise InputError("expected --executor ray with --address", "address")


@dataclass(frozen=True)
class BuildSummary:
    """What a build did: targets in the grid, reached (and written), not reached, skipped (already done), and of the
    poses held on the robustness family, how many did not stand on every member (``robust_failed``)."""

    targets: int
    solved: int
    failed: int
    skipped: int
    seconds: float
    index: str
    robust_checked: int = 0
    robust_failed: int = 0

    def as_dict(self) -> JsonObject:
        """JSON-ready dict."""
        return dict(self.__dict__)


def check_workers(workers: int) -> int:
    """Worker count: 0 means one per core; at most :data:`MAX_WORKERS`."""
    if isinstance(workers, bool) or not isinstance(workers, int) or not 0 <= workers <= MAX_WORKERS:
        raise InputError(f"expected 0 (one per core) to {MAX_WORKERS}, got {workers!r}", "workers")
    return workers or max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM ends a build like Ctrl-C does (complete index, no orphans); only in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def build_library(jobs: Sequence[Job], spec: Spec, out_dir: str | Path, settings: BuildSettings = BuildSettings(),
                  workers: int = 0, spec_path: str | None = None,
                  on_done: Callable[[IndexRow], Any] | None = None, executor: Executor | None = None) -> BuildSummary:
    """Solve every job not already in ``out_dir``'s index (see the module docstring) in worker processes, or as
    Ray tasks (``executor``: :class:`Executor`); returns the summary.

    Raises :class:`Interrupted` (exit code 130) when interrupted (Ctrl-C, SIGTERM), after the workers are ended
    and a complete index is written.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"expected a folder, got a file: {out}", "out")
    workers = check_workers(workers)
    settings.pso.validated()
    if executor is not None and executor.kind == "ray":    # a missing Ray or a bad address: refused before writing
        from op2motion.library.cluster import check_ray

        check_ray(executor.address)
    out.mkdir(parents=True, exist_ok=True)
    rows = load_index(out, spec)
    todo = [j for j in jobs if j.name not in rows]
    t0 = time.perf_counter()
    interrupted = False
    try:
        with _sigterm_as_interrupt():
            record = JobRecorder(out, rows, on_done)
            if todo and executor is not None and executor.kind == "ray":
                from op2motion.library.cluster import run_on_ray

                run_on_ray(todo, spec, spec_text(spec_path), settings, min(workers, len(todo)), record,
                           executor.address)
            elif todo:
                _run(todo, spec, spec_path, settings, min(workers, len(todo)), record)
    except KeyboardInterrupt:
        interrupted = True
    finally:   # every exit path: the index describes exactly the pose files present
        rows = reconcile(out, rows, spec)
        write_index(out, rows)
    if interrupted:
        raise Interrupted(f"library build stopped: {out / INDEX_JSON} lists the {len(rows)} target(s) done; run the "
                          "same command again to resume")
    wanted = [rows[j.name] for j in jobs if j.name in rows]
    solved = sum(1 for r in wanted if r.reached)
    held = [r for r in wanted if r.reached and r.robust_runs]
    return BuildSummary(len(jobs), solved, len(wanted) - solved, len(jobs) - len(todo),
                        round(time.perf_counter() - t0, 2), str(out / "index.json"), len(held),
                        sum(1 for r in held if r.robust_passed != r.robust_runs))


def _run(todo: Sequence[Job], spec: Spec, spec_path: str | None, settings: BuildSettings, workers: int,
         record: JobRecorder) -> None:
    ctx = multiprocessing.get_context("spawn")  # fresh interpreters: no inherited threads or pyswarms state
    pool = None
    try:
        with one_thread_each(), starting_workers():
            pool = ctx.Pool(workers, initializer=worker_init, initargs=(os.getpid(),))
        tasks = [(job, spec_path, spec.sha256, settings, None) for job in todo]
        for row, pose_text in pool.imap_unordered(solve_job, tasks):
            record(row, pose_text)
        pool.close()
    finally:
        if pool is not None:
            pool.terminate()   # on Ctrl-C: pending targets cancelled, workers ended at once
            pool.join()
