"""Figures rendered beside the work that produces their data.

Loading matplotlib takes about 0.4 s and drawing a pose figure another 0.3 s, as long as the whole optimisation.
:class:`Renderers` forks a process that loads matplotlib while the caller computes and then forks one copy per
further figure (loaded once, not once per renderer, so the caller's own start-up is not slowed twice); each draws
one figure on its own core when the data is ready, so the figures of ``optimize`` cost about as much as the
slowest. A staged figure (:meth:`Renderers.begin`) is begun as soon as part of its data is there and finished
with the rest (:meth:`Renderers.finish`): a pose figure is drawn while its pose's physics check runs and gets its
verdict after. Where processes cannot be forked (no ``fork`` start method) or a renderer fails, the figure is drawn
here instead: the bytes are the same either way.
"""

from __future__ import annotations

import contextlib
import importlib
import multiprocessing
import os
import signal
from dataclasses import dataclass
from typing import Any, Callable, Sequence

_WAIT_S = 60.0      # a renderer that has not answered in this long is given up (the figure is drawn here)


def _serve(conns: list[Any], preload: Sequence[str] = ()) -> None:
    """In the first renderer: load matplotlib and the modules ``preload`` (those of the figures it will be asked
    for) once, fork one more renderer per extra pipe (the copies share what was loaded), then each draws the one
    figure asked on its pipe and sends it back."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)            # the parent decides what Ctrl-C ends (it started us
    signal.signal(signal.SIGTERM, signal.SIG_DFL)           # with it ignored); a SIGTERM ends a renderer quietly
    with contextlib.suppress(Exception):
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot  # noqa: F401
        import mpl_toolkits.mplot3d  # noqa: F401

        for module in preload:                              # not when the job's arguments arrive (then it waits)
            importlib.import_module(module)
    for extra in conns[1:]:
        if os.fork() == 0:                                   # a copy, matplotlib loaded: it serves this pipe
            _answer(extra)
            os._exit(0)
    _answer(conns[0])


def _answer(conn: Any) -> None:
    """Draw the one figure asked on ``conn`` and send it back (nothing when the parent sends None or goes). A
    staged job is begun at once and finished with the arguments the parent sends next."""
    try:
        job = conn.recv()
    except (EOFError, OSError):
        return
    if job is None:
        return
    fn, args, staged = job
    try:
        if not staged:
            conn.send(("ok", fn(*args)))
            return
        begun = fn(*args)
        later = conn.recv()
        if later is not None:
            conn.send(("ok", begun.finish(*later)))
    except (EOFError, OSError):
        return
    except Exception as exc:                                 # the parent draws it again and sees the error itself
        with contextlib.suppress(Exception):
            conn.send(("error", repr(exc)))


@dataclass
class _Job:
    """A figure asked of a renderer (``conn``: its pipe; None: drawn here), staged or not, and what a staged one
    is finished with."""

    conn: Any
    fn: Callable[..., Any]
    args: tuple[Any, ...]
    staged: bool
    later: tuple[Any, ...] = ()


class Renderers:
    """Up to ``count`` forked renderers (see the module docstring); use as a context manager, :meth:`submit` a
    figure function with its (picklable) arguments, then :meth:`result` each in turn. ``preload``: the modules of
    those functions, loaded with matplotlib before the data is there."""

    def __init__(self, count: int, preload: Sequence[str] = ()):
        self._idle: list[tuple[Any, Any]] = []
        self._procs: list[Any] = []
        self._jobs: list[_Job] = []
        if "fork" not in multiprocessing.get_all_start_methods():
            return
        from op2motion.processes.workers import starting_workers

        ctx = multiprocessing.get_context("fork")
        try:
            with contextlib.suppress(OSError), starting_workers():     # no Ctrl-C inside the renderer as it forks
                pipes = [ctx.Pipe() for _ in range(count)]
                proc = ctx.Process(target=_serve, args=([child for _, child in pipes], tuple(preload)), daemon=True)
                proc.start()
                self._procs.append(proc)
                for parent, child in pipes:
                    child.close()
                    self._idle.append((proc, parent))
        except BaseException:       # a SIGTERM held while forking: the renderer ends with the command
            self.close()
            raise

    def __enter__(self) -> "Renderers":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def submit(self, fn: Callable[..., Any], *args: Any) -> int:
        """Hand ``fn(*args)`` to an idle renderer (or keep it to draw here); returns the job's number."""
        return self._hand(fn, args, False)

    def begin(self, make: Callable[..., Any], *args: Any) -> int:
        """Hand a staged figure to an idle renderer: ``make(*args)`` runs at once and returns an object whose
        ``finish(*later)`` is the job's result, called when :meth:`finish` gives ``later``."""
        return self._hand(make, args, True)

    def _hand(self, fn: Callable[..., Any], args: tuple[Any, ...], staged: bool) -> int:
        conn = None
        if self._idle:
            _, conn = self._idle.pop(0)
            try:
                conn.send((fn, args, staged))
            except Exception:                                  # unpicklable or a dead renderer: draw it here
                conn.close()                                   # (its renderer sees the pipe close and ends)
                conn = None
        self._jobs.append(_Job(conn, fn, args, staged))
        return len(self._jobs) - 1

    def finish(self, job: int, *later: Any) -> None:
        """Give the staged job ``job`` (:meth:`begin`) what its ``finish`` takes."""
        entry = self._jobs[job]
        entry.later = later
        if entry.conn is not None:
            try:
                entry.conn.send(later)
            except Exception:                                  # unpicklable or a dead renderer: drawn here
                entry.conn.close()
                entry.conn = None

    def result(self, job: int) -> Any:
        """What job ``job`` returned (drawn here if its renderer failed)."""
        entry = self._jobs[job]
        if entry.conn is not None:
            with contextlib.suppress(EOFError, OSError):
                if entry.conn.poll(_WAIT_S):
                    status, value = entry.conn.recv()
                    if status == "ok":
                        return value
        if entry.staged:
            return entry.fn(*entry.args).finish(*entry.later)
        return entry.fn(*entry.args)

    def close(self) -> None:
        """End every renderer."""
        for _, conn in self._idle:
            with contextlib.suppress(Exception):
                conn.send(None)
        for proc in self._procs:
            proc.join(timeout=0.2)
            if proc.is_alive():
                proc.kill()
                proc.join()
        for conn in [c for _, c in self._idle] + [j.conn for j in self._jobs if j.conn is not None]:
            conn.close()
        self._idle, self._procs = [], []
