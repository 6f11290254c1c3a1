"""``library build --executor ray``: the same targets solved as Ray tasks, on this machine or a cluster.

Each target is one task running the same worker function as the process pool (:func:`.jobs.solve_job`); the
driver stays the only writer (pose files atomically, then the index after every target), so a build is resumable
with the same index whichever executor ran it. Tasks carry the spec's text, not its path: a cluster's nodes need
op2motion installed (``pip install 'op2motion[cluster]'``, the same version), not the driver's files. Ray is an
optional extra; asking for it without it installed is an input error that names the extra.
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import socket
import sys
import tempfile
import threading
from typing import Any, Iterator, Sequence

from op2motion.errors import InputError
from op2motion.library.grid import Job
from op2motion.library.jobs import BuildSettings, JobRecorder, solve_job
from op2motion.processes.workers import THREAD_VARIABLES
from op2motion.robot.spec import Spec

CONNECT_TIMEOUT_S = 3.0     # a cluster's head that does not accept a TCP connection in this long is not there [s]
ANSWER_TIMEOUT_S = 3.0      # ... nor one that does not answer the HTTP/2 greeting of Ray's GCS (gRPC) in this long [s]
WAIT_S = 0.25               # the driver waits for results this long at a time, so signals are handled [s]
INIT_TIMEOUT_S = 9.0        # ray.init on an address that passed both: the rest of the 15 s a refusal may take [s]
HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n"
HTTP2_SETTINGS = b"\x00\x00\x00\x04\x00\x00\x00\x00\x00"      # an empty SETTINGS frame (type 4, stream 0)


def check_address(address: str) -> None:
    """Raise :class:`InputError` unless ``address`` (``host:port``, or ``auto``/``ray://...``) is a running Ray head,
    within :data:`CONNECT_TIMEOUT_S` + :data:`ANSWER_TIMEOUT_S`. Ray's own connection retries an absent or foreign
    head for minutes; here a head must accept a TCP connection and answer the HTTP/2 greeting with its SETTINGS
    frame, as the gRPC server of Ray's GCS does (a web server, a database or a silent port does not)."""
    if address == "auto" or "://" in address:
        return
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(f"expected HOST:PORT (e.g. 10.0.0.5:6379) or auto, got {address!r}", "address")
    host = host.strip("[]")
    try:
        conn = socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S)
    except socket.gaierror as exc:
        raise InputError(f"expected a host name or address, got {host!r} ({exc.strerror})", "address") from None
    except OSError as exc:
        raise InputError(f"expected a running Ray cluster at {address}: {exc.strerror or exc}", "address") from None
    with conn:
        try:
            conn.settimeout(ANSWER_TIMEOUT_S)
            conn.sendall(HTTP2_PREFACE + HTTP2_SETTINGS)
            head = b""
            while len(head) < 9:
                chunk = conn.recv(9 - len(head))
                if not chunk:
                    break
                head += chunk
        except OSError:
            head = b""
    if len(head) < 9 or head[3] != 4 or head[5:9] != b"\x00\x00\x00\x00":
        raise InputError(f"expected a Ray cluster's head (its GCS port, e.g. 6379) at {address}, but it does not "
                         f"answer as Ray does", "address")


def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise InputError("expected Ray for --executor ray: install the extra with pip install 'op2motion[cluster]' "
                         "(or '.[cluster]' in the repository)", "executor") from None
    return ray


def check_ray(address: str | None) -> None:
    """Before anything is written: Ray installed, and ``address`` (if any) a running Ray head
    (:func:`check_address`)."""
    ray = _ray()
    if address is not None and not ray.is_initialized():
        check_address(address)


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Ray's messages while it starts and stops (its notices through ``sys.stderr``, and its C++ core's log lines,
    which go straight to file descriptor 2) into a log file under the temp folder, not the user's terminal."""
    log = tempfile.NamedTemporaryFile(prefix="op2motion-ray-", suffix=".log", delete=False)
    saved, previous = os.dup(2), sys.stderr
    try:
        with contextlib.suppress(Exception):
            sys.stderr.flush()
        os.dup2(log.fileno(), 2)
        sys.stderr = io.TextIOWrapper(log, encoding="utf-8", errors="replace", write_through=True)
        yield
    finally:
        with contextlib.suppress(Exception):
            sys.stderr.flush()
        sys.stderr = previous
        os.dup2(saved, 2)
        os.close(saved)


class _Stop:
    """Ctrl-C and SIGTERM while Ray runs: noted, and acted on between Ray's calls (:meth:`check`). An exception
    raised from a signal handler inside Ray's own code crashed the driver (a segmentation fault seen with Ray
    2.60); Ray's ``init`` also installs its own SIGTERM handler, which exits with status 15."""

    def __init__(self) -> None:
        self.requested = False
        self.main = threading.current_thread() is threading.main_thread()
        self.saved = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)} if self.main else {}

    def note(self, signum: int, frame: Any) -> None:
        self.requested = True

    def arm(self) -> None:
        """(Again) note the signals instead of raising (after ``ray.init`` replaced the SIGTERM handler)."""
        for sig in self.saved:
            signal.signal(sig, self.note)

    def check(self) -> None:
        """Raise :class:`KeyboardInterrupt` here, in our code, if a stop was asked for."""
        if self.requested:
            raise KeyboardInterrupt

    def restore(self) -> None:
        for sig, handler in self.saved.items():
            if handler is not None:
                signal.signal(sig, handler)


def _init(ray: Any, address: str | None, workers: int, stop: _Stop) -> None:
    """``ray.init`` in the main thread (Ray ties the processes it starts to the thread that starts them), bounded by
    :data:`INIT_TIMEOUT_S` where a timer can interrupt it (a head that greets as gRPC but is not Ray would keep it
    retrying); a SIGTERM meanwhile (Ray's handler: ``sys.exit(15)``) becomes a stop like any other. Without an
    ``address`` a new Ray starts here (``"local"``): never a cluster someone else started on this machine (plain
    ``ray.init()`` joins the one ``ray start`` left, and dies with it)."""
    import logging

    env = {"env_vars": {name: "1" for name in THREAD_VARIABLES}}     # one maths thread per task
    alarm = signal.getsignal(signal.SIGALRM) if stop.main else None

    def too_long(signum: int, frame: Any) -> None:
        raise TimeoutError(f"no answer in {INIT_TIMEOUT_S:g} s")

    try:
        if stop.main and address is not None:
            signal.signal(signal.SIGALRM, too_long)
            signal.setitimer(signal.ITIMER_REAL, INIT_TIMEOUT_S)
        ray.init(address=address or "local", num_cpus=None if address else workers, include_dashboard=False,
                 log_to_driver=False, configure_logging=False, logging_level=logging.ERROR, runtime_env=env)
    except SystemExit as exc:
        if exc.code != signal.SIGTERM:
            raise
        stop.requested = True
    except (ConnectionError, RuntimeError, ValueError, TimeoutError) as exc:
        raise InputError(f"expected a running Ray cluster at {address!r}: {exc}", "address") from None
    finally:
        if stop.main:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            if alarm is not None:
                signal.signal(signal.SIGALRM, alarm)
            stop.arm()


@contextlib.contextmanager
def ray_session(address: str | None, workers: int) -> Iterator[tuple[Any, _Stop]]:
    """Ray, ready for tasks: ``address`` a running cluster (``127.0.0.1:6379`` or ``auto``; checked first,
    :func:`check_address`), or None to start Ray on this machine with ``workers`` CPUs. Yields Ray and the
    :class:`_Stop` that notes Ctrl-C and SIGTERM (call its ``check`` between Ray's calls). Ray's output goes to a
    log file, not the terminal; a Ray started here is shut down, and ended however the program ends
    (:mod:`.reaper`). Shared by library builds and gait tuning."""
    from op2motion.library.reaper import release, watch

    ray = _ray()
    started = not ray.is_initialized()
    if started and address is not None:
        check_address(address)
    watchdog = watch() if started and address is None else None
    stop = _Stop()
    stop.arm()
    try:
        if started:
            with _quiet_stderr():
                _init(ray, address, workers, stop)
        try:
            stop.check()
            yield ray, stop
        finally:
            if started:
                with _quiet_stderr():
                    ray.shutdown()
    finally:
        stop.restore()
        release(watchdog)


def run_on_ray(todo: Sequence[Job], spec: Spec, spec_text: str, settings: BuildSettings, workers: int,
               record: JobRecorder, address: str | None) -> None:
    """Solve ``todo`` as Ray tasks in a :func:`ray_session` and record each result as it comes; Ctrl-C and
    SIGTERM end the build between Ray's calls."""
    with ray_session(address, workers) as (ray, stop):
        task = ray.remote(num_cpus=1)(solve_job)
        pending = [task.remote((job, None, spec.sha256, settings, spec_text)) for job in todo]
        try:
            while pending:     # short waits: a stop is acted on between them
                stop.check()
                done, pending = ray.wait(pending, num_returns=1, timeout=WAIT_S)
                for ref in done:
                    record(*ray.get(ref))
        finally:
            for ref in pending:               # interrupted: nothing more is solved
                with contextlib.suppress(Exception):
                    ray.cancel(ref, force=True)
