"""What the bus tests share: an emulated OP2 served from this process (a thread; the client under test runs in
another process, or in this one where timing does not matter), and the CLI run as a real subprocess."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
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


def interrupt_after(process: subprocess.Popen, emulator: Emulator, motion_s: float) -> float:
    """Send Ctrl-C (SIGINT) ``motion_s`` simulated seconds after the client's first SYNC_WRITE; the wall time
    [s] it was sent."""
    deadline = time.monotonic() + CLI_TIMEOUT_S
    while time.monotonic() < deadline and process.poll() is None:
        if emulator.motion_t0 is not None and emulator.truth()["t_s"] - emulator.motion_t0 >= motion_s:
            break
        time.sleep(0.01)
    process.send_signal(signal.SIGINT)
    return time.monotonic()
