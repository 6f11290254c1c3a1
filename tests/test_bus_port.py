"""The robot's serial port on real pseudo-terminals: a port that hangs up (its other side closed: the USB adapter
unplugged) fails at once as :class:`PortFailed` naming it, in one line, at open (a terminal error), in a command
(``robot status``) and mid-motion (the run ends as the fault ``port failed``, its JSON still printed); a port another
process holds open is refused naming that process unless ``--shared-port``, while a bridge that holds only the
pseudo-terminal's other side (the emulator's way) is not holding the port; a path with a newline stays on one line."""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
import sys
import threading
import time
from typing import Iterator

import pytest
from bus_support import robot_json
from helpers import POSES, run_cli

from op2motion.bus import protocol as p
from op2motion.bus.port import open_port
from op2motion.bus.tables import SYNC_SPAN
from op2motion.errors import InputError, PortFailed, one_line, shown

HANG_UP_AFTER_S = 0.05         # the other side closes this long into a read
HANG_UP_SEEN_S = 0.5           # ... and the read fails well before its own deadline
READ_DEADLINE_S = 5.0
HANG_UP_AT_SYNC = 40           # mid-motion: the pseudo-terminal hangs up after this many of the loop's sync writes
HOLDER_EXIT_S = 20.0           # a holder process, killed, is waited for this long

#: Holders in processes of their own, each printing the pseudo-terminal's terminal side once it holds what it holds:
#: a second program with the terminal side open; a bridge holding only the other side (the emulator's way, or socat
#: with wait-slave); a bridge holding both (socat's pty by default: openpty, the terminal side kept open).
OPENS_PATH = "import sys, time; f = open(sys.argv[1], 'rb'); print(sys.argv[1], flush=True); time.sleep(60)"
HOLDS_MASTER = ("import os, time; m, s = os.openpty(); name = os.ttyname(s); os.close(s); print(name, flush=True); "
                "time.sleep(60)")
HOLDS_BOTH = "import os, time; m, s = os.openpty(); print(os.ttyname(s), flush=True); time.sleep(60)"


class PseudoTerminal:
    """A pseudo-terminal whose terminal side only the test opens (``name``); :meth:`hang_up` closes its other side
    (once, from any thread: a closed descriptor's number may be reused at once)."""

    def __init__(self):
        self.master, slave = os.openpty()
        self.name = os.ttyname(slave)
        os.close(slave)
        self.lock, self.up = threading.Lock(), True

    def hang_up(self) -> None:
        with self.lock:
            if self.up:
                self.up = False
                os.close(self.master)


@contextlib.contextmanager
def pseudo_terminal() -> Iterator[PseudoTerminal]:
    pty = PseudoTerminal()
    try:
        yield pty
    finally:
        pty.hang_up()


@contextlib.contextmanager
def holder(script: str, *args: str) -> Iterator[tuple[subprocess.Popen, str]]:
    """``script`` in a process of its own: (the process, the terminal side's path it printed once ready)."""
    process = subprocess.Popen([sys.executable, "-c", script, *args], stdout=subprocess.PIPE, text=True)
    try:
        name = process.stdout.readline().strip()
        assert name.startswith("/dev/"), name
        yield process, name
    finally:
        process.kill()
        process.wait(HOLDER_EXIT_S)


def _error_line(err: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("op2motion: error: "), err
    return lines[0]


def test_a_port_that_hangs_up_mid_read_fails_at_once_naming_it():
    with pseudo_terminal() as pty:
        name = pty.name
        port = open_port(name)
        try:
            threading.Timer(HANG_UP_AFTER_S, pty.hang_up).start()
            started = time.monotonic()
            with pytest.raises(PortFailed, match="hung up") as read:
                port.read(started + READ_DEADLINE_S)
            assert time.monotonic() - started < HANG_UP_SEEN_S
            with pytest.raises(PortFailed, match="writing to .* failed: Input/output error") as write:
                port.write(b"\xff\xff\xc8\x02\x01\x34")
            with pytest.raises(PortFailed, match="hung up"):
                port.flush_input()
        finally:
            port.close()
    for e in (read.value, write.value):
        assert e.exit_code == 1 and e.param == "port" and name in e.message and "\n" not in str(e)


def test_a_terminal_error_as_the_port_opens_is_a_port_failure(monkeypatch, capsys):
    """pyserial's open sets the terminal up with tcsetattr and tcflush, whose ``termios.error`` is no ``OSError``:
    it must still end as one line naming the port, exit 1 (it was an internal error)."""
    import termios

    import serial

    def hung_up(self: serial.Serial) -> None:
        raise termios.error(errno.EIO, "Input/output error")

    with pseudo_terminal() as pty:
        name = pty.name
        monkeypatch.setattr(serial.Serial, "open", hung_up)
        with pytest.raises(PortFailed, match="opening .* failed: Input/output error"):
            open_port(name)
        code, out, err = run_cli(capsys, "robot", "status", "--port", name, "--json")
    line = _error_line(err)
    assert code == 1 and out == "" and line.startswith(f"op2motion: error: --port: opening {name} failed")


def test_robot_status_on_a_port_that_hangs_up_is_one_line(capsys):
    """The robot's end hangs up as the first request comes (the USB cable pulled as the command starts)."""
    with pseudo_terminal() as pty:
        name = pty.name

        def hang_up_on_first_request() -> None:
            deadline = time.monotonic() + READ_DEADLINE_S
            while time.monotonic() < deadline:
                try:
                    if os.read(pty.master, 64):
                        break
                except OSError:                              # the command has not opened its side yet
                    time.sleep(0.001)
            pty.hang_up()

        robot = threading.Thread(target=hang_up_on_first_request, daemon=True)
        robot.start()
        code, out, err = run_cli(capsys, "robot", "status", "--port", name, "--json")
        robot.join(READ_DEADLINE_S)
    line = _error_line(err)
    assert code == 1 and out == "" and f"--port: {name} hung up" in line and "internal error" not in line


class HangsUpMidRun:
    """An emulated OP2's port in lockstep that, after its ``at``-th sync write (one a tick of the 8 ms loop), goes
    over to a real pseudo-terminal and closes that terminal's other side: from then on the bus meets what a hung-up
    terminal really does (reads of nothing, EIO on writes)."""

    def __init__(self, inner, at: int):
        self.inner, self.at, self.syncs = inner, at, 0
        self.path, self.clock, self.emulator = inner.path, inner.clock, inner.emulator
        self.latency_timer_ms, self.low_latency = inner.latency_timer_ms, inner.low_latency
        self.pty = PseudoTerminal()
        self.name = self.pty.name
        self.real = open_port(self.name)
        self.now = inner

    def write(self, data: bytes) -> None:
        self.now.write(data)
        self.syncs += data[4] == p.Instruction.SYNC_WRITE and tuple(data[5:7]) == SYNC_SPAN     # the loop's
        if self.syncs == self.at and self.now is self.inner:
            self.pty.hang_up()                             # the adapter unplugged after this tick's write
            self.now = self.real

    def read(self, deadline: float) -> bytes:
        return self.now.read(deadline)

    def flush_input(self) -> bytes:
        return self.now.flush_input()

    def close(self) -> None:
        self.real.close()
        self.pty.hang_up()
        self.inner.close()


@pytest.mark.physics
def test_a_port_that_hangs_up_mid_motion_ends_it_as_a_fault_with_its_json(monkeypatch, capsys):
    from op2motion.bus.emulator import lockstep

    made: list[HangsUpMidRun] = []
    real_robot = lockstep.lockstep_robot

    def hanging_robot(text, spec):
        made.append(HangsUpMidRun(real_robot(text, spec), HANG_UP_AT_SYNC))
        return made[-1]

    monkeypatch.setattr(lockstep, "lockstep_robot", hanging_robot)
    code, result, err = robot_json(capsys, "robot", "play", "--port", "lockstep", "--force",
                                   str(POSES / "walkready.json"))
    name = made[0].name
    line = _error_line(err)
    assert code == 1 and line.startswith("op2motion: error: pose walkready stopped: the serial port failed: ")
    assert f"{name} hung up" in line
    motion = result["runs"]["motion"]
    assert result["ended"] == "fault" and result["fault"]["kind"] == "port failed" and name in result["fault"]["text"]
    assert motion["ended"] == "fault" and motion["ticks"] == HANG_UP_AT_SYNC     # every tick before it, reported


def test_a_port_another_process_holds_is_refused_naming_it_unless_shared(capsys):
    with pseudo_terminal() as pty, holder(OPENS_PATH, pty.name) as (process, name):
        with pytest.raises(InputError, match=f"busy: process {process.pid} \\(python[^)]*\\) holds {name} open") \
                as refused:
            open_port(name)
        assert refused.value.param == "port"
        open_port(name, shared=True).close()
        code, _, err = run_cli(capsys, "robot", "status", "--port", name)
        line = _error_line(err)
        assert code == 2 and f"--port: busy: process {process.pid} (" in line and line.endswith("--shared-port")
        code, _, err = run_cli(capsys, "robot", "status", "--port", name, "--shared-port")
        assert code == 2 and "nothing answers at ID 200" in _error_line(err)     # opened: nobody answers on it


def test_a_bridge_holding_only_the_other_side_is_not_holding_the_port():
    """The emulator (and socat with wait-slave) holds only the master side: the far end of the wire, opened without
    ``--shared-port``; socat's pty by default keeps the terminal side open too: refused, named, unless shared."""
    with holder(HOLDS_MASTER) as (_, name):
        open_port(name).close()
    with holder(HOLDS_BOTH) as (process, name):
        with pytest.raises(InputError, match=f"process {process.pid} "):
            open_port(name)
        open_port(name, shared=True).close()


def test_a_path_with_a_newline_stays_one_line(capsys):
    bad = "/dev/tty\nUSB0"
    code, out, err = run_cli(capsys, "robot", "status", "--port", bad)
    assert code == 2 and out == "" and _error_line(err) == (
        "op2motion: error: --port: no such serial port: '/dev/tty\\nUSB0' (is the robot's USB cable plugged in and "
        "the robot on?)")
    assert shown("/dev/ttyUSB0") == "/dev/ttyUSB0" and shown(" /dev/ttyUSB0") == "' /dev/ttyUSB0'"
    assert one_line("a\nb\r\x1b\u2028c °") == "a\\nb\\r\\x1b\\u2028c °"


def test_any_message_the_command_line_prints_is_one_line(capsys, tmp_path):
    """A path quoted by a message that does not escape it itself (a pose file's) is escaped where errors are
    printed."""
    code, _, err = run_cli(capsys, "fk", "--pose", str(tmp_path / "a\nb.json"), "--json")
    assert code == 2 and "a\\nb.json" in _error_line(err)


def test_studio_shared_port_needs_a_robot(capsys):
    code, _, err = run_cli(capsys, "studio", "--shared-port", "--port", "0")
    assert code == 2 and _error_line(err).startswith("op2motion: error: --shared-port: expected --robot")

