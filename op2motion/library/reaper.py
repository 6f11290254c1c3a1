"""No orphans after the driver dies, however it dies: a watchdog process that ends every process a Ray session left.

Ray started on this machine (``library build --executor ray`` without ``--address``) runs a GCS server, a raylet,
agents and worker processes. ``ray.shutdown()`` ends them, and Ray ties its GCS and raylet to the driver, but after a
``kill -9`` of the driver its agents and idle workers lived on (seen with Ray 2.60). :func:`watch` marks the
environment that Ray's processes inherit (:data:`MARK`) and starts a small watchdog in its own session: it waits for
the driver's end (the pipe to it closes, whatever the cause) and then kills every process of the driver's Ray session
and nothing else: the processes carrying the driver's mark, those whose command line names the session's folder
(Ray names it ``session_<date>_<time>_<driver's pid>``: the GCS server, the raylet, its monitors), and every process
below them (the agents and workers the raylet started, whose environment is their own). Another driver's Ray in the
same process group (two builds started from one shell, two tests) is left alone. The watchdog reads ``/proc``
(Linux); elsewhere it does nothing.
"""

from __future__ import annotations

import os
import subprocess
import sys

MARK = "OP2MOTION_RAY_OWNER"       # set to the driver's pid in the environment Ray's processes inherit

_WATCHDOG = r"""
import os, re, signal, sys
mark, driver = sys.argv[1].encode(), sys.argv[2]
sys.stdin.buffer.read()                       # returns when the driver ends (the pipe closes)
session = re.compile(rb"/session_[0-9_-]+_" + driver.encode() + rb"(?![0-9])")
me, parent, found = str(os.getpid()), {}, []
for pid in os.listdir("/proc"):
    if not pid.isdigit() or pid in (me, driver):
        continue
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            parent[pid] = f.read().rsplit(b")", 1)[1].split()[1].decode()
        with open(f"/proc/{pid}/environ", "rb") as f:
            marked = mark in f.read().split(b"\0")
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            if marked or session.search(f.read()):
                found.append(pid)
    except OSError:
        pass
children = {}
for pid, ppid in parent.items():
    children.setdefault(ppid, []).append(pid)
doomed = set()
while found:
    pid = found.pop()
    if pid not in doomed:
        doomed.add(pid)
        found.extend(children.get(pid, []))
for pid in doomed:
    try:
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
    return subprocess.Popen([sys.executable, "-c", _WATCHDOG, f"{MARK}={os.getpid()}", str(os.getpid())],
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
