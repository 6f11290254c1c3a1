"""What the bus tests share: an emulated OP2 in a process of its own (``op2motion robot emulate``, as it would run
beside a client: a motion's 8 ms loop needs it answering on time, which a thread of the test's busy interpreter
cannot promise) or, where no motion runs, served from this process; and the CLI run as a real subprocess."""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

from helpers import ROOT

from op2motion.bus.emulator.faults import Faults
from op2motion.bus.emulator.server import Emulator
from op2motion.robot.spec import Spec

CLI_TIMEOUT_S = 120.0


@contextlib.contextmanager
def emulated(spec: Spec, folder: Path, engine: str = "mujoco", start: str = "standing",
             faults: Faults | None = None) -> Iterator[tuple[Emulator, str]]:
    """An emulated OP2 serving in a thread; yields it and the path of its port."""
    emulator = Emulator(spec, engine, start, faults)
    link = str(folder / f"op2-{engine}-{start}")
    emulator.open(link)
    emulator.start()
    try:
        yield emulator, link
    finally:
        emulator.close()


class EmulatorProcess:
    """``op2motion robot emulate`` running in its own process: its port (``link``), and what it reports
    (``--truth``: :meth:`report`, :meth:`truth`)."""

    def __init__(self, folder: Path, engine: str, start: str, flags: tuple[str, ...]):
        self.link, self.path = str(folder / f"op2-{engine}-{start}"), folder / f"truth-{engine}-{start}.json"
        self.process = cli("robot", "emulate", "--link", self.link, "--engine", engine, "--start", start,
                           "--truth", str(self.path), *flags)
        deadline = time.monotonic() + CLI_TIMEOUT_S
        while not (os.path.lexists(self.link) and self.path.exists()):
            if self.process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the emulated OP2 did not start: {self.process.communicate()[1]}")
            time.sleep(0.02)

    def report(self) -> dict:
        """The emulator's latest report (torso, motion time, servos' goals and torque limits, counters)."""
        for _ in range(100):
            try:
                return json.loads(self.path.read_text().strip())
            except (OSError, ValueError):                 # not there yet, or caught half written
                time.sleep(0.01)
        raise RuntimeError("no report from the emulated OP2")

    def truth(self) -> dict:
        """The simulated torso now."""
        return self.report()["truth"]

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
        try:
            self.process.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.communicate()


#: One real-time bus at a time across the test workers: an emulator and a client loop both run at real-time priority,
#: and two such pairs on a 2-core machine starve each other (a blind bus is then the right verdict, and the test fails).
REALTIME_LOCK = Path(tempfile.gettempdir()) / "op2motion-tests-realtime-bus.lock"


@contextlib.contextmanager
def _one_realtime_bus() -> Iterator[None]:
    with open(REALTIME_LOCK, "a") as lock:
        fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock.fileno(), fcntl.LOCK_UN)


@contextlib.contextmanager
def emulator_process(folder: Path, engine: str = "mujoco", start: str = "standing", *flags: str
                     ) -> Iterator[EmulatorProcess]:
    """An emulated OP2 in its own process, with the faults given as ``robot emulate`` flags (one at a time across
    the test workers: :data:`REALTIME_LOCK`)."""
    with _one_realtime_bus():
        emulator = EmulatorProcess(folder, engine, start, flags)
        try:
            yield emulator
        finally:
            emulator.close()


def cli(*argv: str, timeout: float = CLI_TIMEOUT_S) -> subprocess.Popen:
    """``op2motion ARGV`` started as a subprocess (stdout and stderr piped)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "op2motion", *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=ROOT, env=env)


def finish(process: subprocess.Popen, timeout: float = CLI_TIMEOUT_S) -> tuple[int, str, str]:
    """Wait for a CLI subprocess: (exit code, stdout, stderr)."""
    out, err = process.communicate(timeout=timeout)
    return process.returncode, out, err


def run(*argv: str, timeout: float = CLI_TIMEOUT_S) -> tuple[int, str, str]:
    """``op2motion ARGV`` in a subprocess, to its end."""
    return finish(cli(*argv), timeout)


#: The one outcome a motion test retries once: the whole bus silent for 40 ms. A pseudo-terminal's bytes are moved by
#: a kernel worker thread at normal priority (the loop and the emulator run at real-time priority); on a machine
#: loaded far beyond its cores that worker alone can stall the port that long, and the loop stops, as it must.
BLIND_BUS = "the sub-controller (ID 200): not answering"


def run_motion(*argv: str) -> tuple[int, str, str]:
    """``op2motion ARGV`` (a motion expected to succeed), run again once if the whole bus went blind (see
    :data:`BLIND_BUS`); a fault of any single servo, or a second blind bus, is reported as it came."""
    code, out, err = run(*argv)
    if code == 1 and BLIND_BUS in err:
        code, out, err = run(*argv)
    return code, out, err


def interrupt_when_walked(process: subprocess.Popen, emulator: EmulatorProcess, x_m: float) -> float:
    """Send Ctrl-C (SIGINT) once the emulated torso has walked ``x_m`` [m] forward (mid-walk); the wall time [s] it
    was sent."""
    start = emulator.truth()["x_m"]
    deadline = time.monotonic() + CLI_TIMEOUT_S
    while time.monotonic() < deadline and process.poll() is None:
        if emulator.truth()["x_m"] - start >= x_m:
            break
        time.sleep(0.02)
    process.send_signal(signal.SIGINT)
    return time.monotonic()
