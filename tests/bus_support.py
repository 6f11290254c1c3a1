"""What the bus tests share.

Most run the emulated OP2 **in lockstep** in the test's own process (:func:`lockstep`, or ``--port lockstep:...`` on
the command line): the client, the wire model (1 Mbps, return delays, the FTDI's packets and a 1 ms latency timer)
and the physics advance together in simulated time, deterministically and faster than real time, whatever else the
machine is doing. A few end-to-end tests run it in real time in a process of its own (:func:`emulator_process`,
``op2motion robot emulate``) on a real pseudo-terminal, as a user would, with the CLI as a real subprocess
(:func:`cli`).
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Iterator

from helpers import ROOT

from op2motion.bus.emulator.faults import Faults
from op2motion.bus.emulator.lockstep import LockstepPort
from op2motion.bus.emulator.server import Emulator
from op2motion.bus.emulator.timing import WireTiming
from op2motion.robot.spec import Spec

CLI_TIMEOUT_S = 120.0
WIRE_1MS = WireTiming(latency_timer_s=0.001)   # the real wire, the latency timer op2motion sets


@contextlib.contextmanager
def lockstep(spec: Spec, engine: str = "mujoco", start: str = "standing", faults: Faults | None = None,
             timing: WireTiming = WIRE_1MS, return_delay: int | None = None, pace: float | None = None
             ) -> Iterator[tuple[Emulator, LockstepPort]]:
    """An emulated OP2 in lockstep in this process; yields it and its port (pass the port where a path would go;
    ``pace``: held to that many simulated seconds a wall second, for tests that act by the wall clock)."""
    emulator = Emulator(spec, engine, start, faults, timing=timing, return_delay=return_delay)  # type: ignore[arg-type]
    try:
        yield emulator, LockstepPort(emulator, pace=pace)
    finally:
        emulator.close()


def robot_json(capsys, *argv: str) -> tuple[int, dict | None, str]:
    """``op2motion ARGV --json`` in this process (an ``--port lockstep:...`` robot): (exit code, the JSON result or
    None, stderr)."""
    from helpers import run_cli

    code, out, err = run_cli(capsys, *argv, "--json")
    return code, json.loads(out) if out.strip() else None, err


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


@contextlib.contextmanager
def emulator_process(folder: Path, engine: str = "mujoco", start: str = "standing", *flags: str
                     ) -> Iterator[EmulatorProcess]:
    """An emulated OP2 in real time in its own process, with ``robot emulate`` flags (its wire: real, 1 ms)."""
    emulator = EmulatorProcess(folder, engine, start, flags)
    try:
        yield emulator
    finally:
        emulator.close()


def cli(*argv: str, stdin: int = subprocess.PIPE) -> subprocess.Popen:
    """``op2motion ARGV`` started as a subprocess (stdout and stderr piped; stdin piped unless given, e.g. the
    terminal end of a pseudo-terminal)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "op2motion", *argv], stdin=stdin,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env)


def stderr_until(process: subprocess.Popen, text: str, timeout: float = CLI_TIMEOUT_S) -> str:
    """What a CLI subprocess printed on stderr up to and including ``text`` (read as it comes; the rest is left for
    :func:`finish`)."""
    assert process.stderr is not None
    fd, got = process.stderr.fileno(), b""
    deadline = time.monotonic() + timeout
    while text.encode() not in got:
        chunk = os.read(fd, 4096) if select.select([fd], [], [], 0.05)[0] else None
        if chunk == b"" or time.monotonic() > deadline:                   # ended, or still silent
            raise RuntimeError(f"expected {text!r} on stderr, got {got.decode(errors='replace')!r}")
        got += chunk or b""
    return got.decode(errors="replace")


def finish(process: subprocess.Popen, timeout: float = CLI_TIMEOUT_S) -> tuple[int, str, str]:
    """Wait for a CLI subprocess: (exit code, stdout, stderr)."""
    out, err = process.communicate(timeout=timeout)
    return process.returncode, out, err


def run(*argv: str, timeout: float = CLI_TIMEOUT_S) -> tuple[int, str, str]:
    """``op2motion ARGV`` in a subprocess, to its end."""
    return finish(cli(*argv), timeout)
