"""``library build --executor ray``: the same targets solved as Ray tasks, on this machine or a cluster.

Each target is one task running the same worker function as the process pool (:func:`.jobs.solve_job`); the
driver stays the only writer (pose files atomically, then the index after every target), so a build is resumable
with the same index whichever executor ran it. Tasks carry the spec's text, not its path: a cluster's nodes need
op2motion installed (``pip install 'op2motion[cluster]'``, the same version), not the driver's files. Ray is an
optional extra; asking for it without it installed is an input error that names the extra.
"""

from __future__ import annotations

import socket
from typing import Any, Sequence

from op2motion.errors import InputError
from op2motion.library.grid import Job
from op2motion.library.jobs import THREAD_VARIABLES, BuildSettings, Recorder, solve_job
from op2motion.robot.spec import Spec

CONNECT_TIMEOUT_S = 5.0     # a cluster's head that does not answer a TCP connection in this long is not there


def _reachable(address: str) -> None:
    """Raise :class:`InputError` unless ``address`` (``host:port``, or ``auto``/``ray://...``) accepts a connection
    (Ray itself retries an absent head for minutes)."""
    if address == "auto" or "://" in address:
        return
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise InputError(f"expected HOST:PORT (e.g. 10.0.0.5:6379) or auto, got {address!r}", "address")
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise InputError(f"expected a running Ray cluster at {address}: {exc.strerror or exc}", "address") from None


def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise InputError("expected Ray for --executor ray: install the extra with pip install 'op2motion[cluster]' "
                         "(or '.[cluster]' in the repository)", "executor") from None
    return ray


def run_on_ray(todo: Sequence[Job], spec: Spec, spec_text: str, settings: BuildSettings, workers: int,
               record: Recorder, address: str | None) -> None:
    """Solve ``todo`` as Ray tasks (``address``: a running cluster, e.g. ``127.0.0.1:6379`` or ``auto``; None starts
    Ray on this machine with ``workers`` CPUs) and record each result as it comes."""
    ray = _ray()
    started = not ray.is_initialized()
    if started and address is not None:
        _reachable(address)
    if started:
        env = {"env_vars": {name: "1" for name in THREAD_VARIABLES}}     # one maths thread per task
        try:
            ray.init(address=address, num_cpus=None if address else workers, include_dashboard=False,
                     log_to_driver=False, configure_logging=False, runtime_env=env)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            raise InputError(f"expected a running Ray cluster at {address!r}: {exc}", "address") from None
    task = ray.remote(num_cpus=1)(solve_job)
    pending = [task.remote((job, None, spec.sha256, settings, spec_text)) for job in todo]
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            record(*ray.get(done[0]))
    finally:
        for ref in pending:               # interrupted: nothing more is solved
            ray.cancel(ref, force=True)
        if started:
            ray.shutdown()
