"""No orphans after the driver dies, however it dies: a watchdog process that ends every process a Ray session left.

Ray started on this machine (``library build --executor ray`` without ``--address``) runs a GCS server, a raylet,
agents and worker processes. ``ray.shutdown()`` ends them, and Ray ties its GCS and raylet to the driver, but after a
``kill -9`` of the driver its agents and idle workers lived on (seen with Ray 2.60). :func:`watch` marks the
environment that Ray's processes inherit (:data:`MARK`) and starts a small watchdog in its own session: it waits for
the driver's end (the pipe to it closes, whatever the cause) and then kills every process carrying the driver's mark,
and every Ray process in the driver's process group (Ray's agents start with an environment of their own). The
watchdog reads ``/proc`` (Linux); elsewhere it does nothing.
"""

from __future__ import annotations

import os
import subprocess
import sys

MARK = "OP2MOTION_RAY_OWNER"       # set to the driver's pid in the environment Ray's processes inherit

_WATCHDOG = r"""
import os, signal, sys
mark, group, driver = sys.argv[1].encode(), int(sys.argv[2]), sys.argv[3]
sys.stdin.buffer.read()                       # returns when the driver ends (the pipe closes)
me = str(os.getpid())
for pid in os.listdir("/proc"):
    if not pid.isdigit() or pid in (me, driver):
        continue
    try:
        with open(f"/proc/{pid}/environ", "rb") as f:
            marked = mark in f.read().split(b"\0")
        if not marked and os.getpgid(int(pid)) == group:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read()
            marked = b"ray::" in cmd or b"/ray/" in cmd              # Ray's programs, scripts and workers
        if marked:
            os.kill(int(pid), signal.SIGKILL)
    except OSError:
        pass
"""


def watch() -> subprocess.Popen[bytes] | None:
    """Mark this process's environment (:data:`MARK`) and start the watchdog (see the module docstring); returns it
    (None where there is no ``/proc``). Call before Ray starts its processes."""
    if not os.path.isdir("/proc"):
        return None
    os.environ[MARK] = str(os.getpid())
    return subprocess.Popen([sys.executable, "-c", _WATCHDOG, f"{MARK}={os.getpid()}", str(os.getpgid(0)),
                             str(os.getpid())],
                            stdin=subprocess.PIPE,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                            close_fds=True)


def release(watchdog: subprocess.Popen[bytes] | None) -> None:
    """After ``ray.shutdown()``: close the pipe, so the watchdog ends whatever Ray left, and exits."""
    if watchdog is None:
        return
    os.environ.pop(MARK, None)
    if watchdog.stdin is not None:
        watchdog.stdin.close()
    try:
        watchdog.wait(timeout=5.0)
    except subprocess.TimeoutExpired:
        watchdog.kill()
