"""No orphans after the driver dies, however it dies: a watchdog process that ends every process a Ray session left.

Ray started on this machine (``library build --executor ray`` without ``--address``) runs a GCS server, a raylet,
agents and worker processes. ``ray.shutdown()`` ends them, and Ray ties its GCS and raylet to the driver, but after a
``kill -9`` of the driver its agents and idle workers lived on (seen with Ray 2.60). :func:`watch` marks the
environment that Ray's processes inherit (:data:`MARK`) and starts a small watchdog in its own session: it waits for
the driver's end (the pipe to it closes, whatever the cause), noting the driver's descendants twice a second, and
then kills every process of the driver's Ray session and nothing else: those it saw below the driver (the same
process: same start time), those carrying the driver's mark, those naming the session's folder on their command line
or in a file they hold open (Ray names it ``session_<date>_<time>_<driver's pid>``: the GCS server, the raylet, its
monitors; the agents log there, their environment their own), and every process below any of them. Another driver's
Ray in the same process group (two builds started from one shell, two tests) is left alone. The watchdog reads ``/proc``
(Linux); elsewhere it does nothing.
"""

from __future__ import annotations

import os
import subprocess
import sys

MARK = "OP2MOTION_RAY_OWNER"       # set to the driver's pid in the environment Ray's processes inherit

_WATCHDOG = r"""
import os, re, select, signal, sys
mark, driver = sys.argv[1].encode(), sys.argv[2]
session = re.compile(rb"/session_[0-9_-]+_" + driver.encode() + rb"(?![0-9])")
me = str(os.getpid())


def table():
    # pid -> (parent pid, start time) of every process but this one and the driver
    out = {}
    for pid in os.listdir("/proc"):
        if pid.isdigit() and pid not in (me, driver):
            try:
                with open(f"/proc/{pid}/stat", "rb") as f:
                    fields = f.read().rsplit(b")", 1)[1].split()
                out[pid] = (fields[1].decode(), fields[19])
            except OSError:
                pass
    return out


def below(roots, procs):
    children = {}
    for pid, (ppid, _) in procs.items():
        children.setdefault(ppid, []).append(pid)
    found, todo = set(), list(roots)
    while todo:
        pid = todo.pop()
        if pid not in found:
            found.add(pid)
            todo.extend(children.get(pid, []))
    return found


def ours(pid):
    # marked, or naming the driver's session folder on its command line or in an open file
    try:
        with open(f"/proc/{pid}/environ", "rb") as f:
            if mark in f.read().split(b"\0"):
                return True
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            if session.search(f.read()):
                return True
        return any(session.search(os.readlink(f"/proc/{pid}/fd/{fd}").encode()) for fd in os.listdir(f"/proc/{pid}/fd"))
    except OSError:
        return False


seen = {}                                     # the driver's descendants while it ran: pid -> start time
while True:
    ready, _, _ = select.select([sys.stdin], [], [], 0.5)
    procs = table()
    seen.update((pid, procs[pid][1]) for pid in below([driver], {**procs, driver: ("", b"")}) if pid in procs)
    if ready and not os.read(sys.stdin.fileno(), 4096):
        break                                 # the pipe closed: the driver ended
procs = table()
roots = [pid for pid in procs if seen.get(pid) == procs[pid][1] or ours(pid)]
for pid in below(roots, procs):
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
