"""The robot's serial port, opened safely, with bounded timeouts everywhere.

:func:`open_port` refuses, as bad input naming ``--port`` (exit 2), a path that does not exist, that is not a
character device, whose device is not a terminal (checked against ``/proc/devices`` *before* opening: opening some
character devices, a watchdog for one, has effects), and a port another program holds: an advisory lock
(``flock``) that every op2motion process takes, and for a real serial device a scan of the other processes' open
files (the stock framework takes no lock) and then ``TIOCEXCL`` so that nobody else opens it while we drive the
robot. A pseudo-terminal (an emulated robot) gets the lock only: its other side belongs to the emulator, which may
well hold the terminal side open too. The port runs at
1 Mbps, raw. A USB serial adapter's latency timer is set to 1 ms (:func:`low_latency`: ``ASYNC_LOW_LATENCY``, and
the ``latency_timer`` file in sysfs where the driver has one and we may write it) and read back, so that what was
achieved is known (:attr:`Port.latency_timer_ms`, :attr:`Port.low_latency`) rather than hoped for; a
pseudo-terminal has none.

:class:`Port` reads and writes with deadlines (``select``): nothing here blocks forever. A port that fails mid-run
(the USB cable pulled) raises :class:`PortFailed` (a check that ran and failed: exit 1).
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import stat
import time
from pathlib import Path
from typing import Any, Protocol

from op2motion.bus.clock import REAL, Clock
from op2motion.errors import CheckFailed, InputError

BAUD = 1_000_000                   # the OP2's bus: Dynamixel baud number 1
WRITE_TIMEOUT_S = 0.05             # a write that cannot go out in this long means the port is stuck
READ_CHUNK = 4096
TTY_DRIVERS = ("tty", "pts", "ttyS", "ttyUSB", "ttyACM", "ttyAMA", "usb/tty", "/dev/tty")
PARAM = "port"
SYSFS_TIMER = "/sys/bus/usb-serial/devices/{name}/latency_timer"


class PortFailed(CheckFailed):
    """The port stopped working mid-run (unplugged, I/O error, stuck)."""


def sysfs_timer_path(port_path: str) -> str:
    """Where Linux's ftdi_sio shows the port's latency timer (for ``/dev/ttyUSB0``:
    ``/sys/bus/usb-serial/devices/ttyUSB0/latency_timer``)."""
    name = os.path.basename(os.path.realpath(port_path)) if port_path.startswith("/") else "ttyUSB0"
    return SYSFS_TIMER.format(name=name if name.startswith("ttyUSB") else "ttyUSB0")


def _drivers() -> dict[int, set[str]] | None:
    """Character-device drivers by major number, from ``/proc/devices`` (None where there is none)."""
    try:
        text = Path("/proc/devices").read_text()
    except OSError:
        return None
    drivers: dict[int, set[str]] = {}
    for line in text.split("Block", 1)[0].splitlines():
        parts = line.split(None, 1)
        if len(parts) == 2 and parts[0].isdigit():
            drivers.setdefault(int(parts[0]), set()).add(parts[1].strip())
    return drivers


def _is_tty(names: set[str]) -> bool:
    return any(n == d or n.startswith(d) for n in names for d in TTY_DRIVERS)


def is_pseudo_terminal(device: os.stat_result) -> bool:
    """Whether ``device`` is the terminal side of a pseudo-terminal (an emulator's port: its other side is, by
    design, held by the program that made it)."""
    drivers = _drivers()
    return drivers is not None and "pts" in drivers.get(os.major(device.st_rdev), set())


def _check_device(path: str) -> os.stat_result:
    """The device's stat; bad input if it is missing, unreadable, not a character device or not a terminal."""
    if not path or not path.strip():
        raise InputError("expected the robot's serial port (e.g. /dev/ttyUSB0), got an empty string", PARAM)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"no such serial port: {path} (is the robot's USB cable plugged in and the robot on?)",
                         PARAM) from None
    except PermissionError:
        raise InputError(f"permission denied: {path} (add yourself to the 'dialout' group)", PARAM) from None
    except OSError as exc:
        raise InputError(f"cannot use {path}: {exc.strerror or exc}", PARAM) from None
    if not stat.S_ISCHR(st.st_mode):
        kind = "directory" if stat.S_ISDIR(st.st_mode) else "regular file" if stat.S_ISREG(st.st_mode) else \
            "block device" if stat.S_ISBLK(st.st_mode) else "socket or pipe"
        raise InputError(f"expected a serial device, got a {kind}: {path}", PARAM)
    drivers = _drivers()
    if drivers is not None and not _is_tty(drivers.get(os.major(st.st_rdev), set())):
        raise InputError(f"expected a serial device, got another kind of character device: {path}", PARAM)
    return st


def holders(device: os.stat_result, skip: int | None = None) -> list[tuple[int, str]]:
    """Other processes with the character device ``device`` open: (pid, command name), as far as ``/proc`` shows
    (processes of other users may be hidden)."""
    found = []
    skip = os.getpid() if skip is None else skip
    for entry in Path("/proc").iterdir() if Path("/proc").is_dir() else ():
        if not entry.name.isdigit() or int(entry.name) == skip:
            continue
        try:
            fds = list((entry / "fd").iterdir())
        except OSError:
            continue
        for fd in fds:
            try:
                st = os.stat(fd)
            except OSError:
                continue
            if stat.S_ISCHR(st.st_mode) and st.st_rdev == device.st_rdev:
                try:
                    name = (entry / "comm").read_text().strip()
                except OSError:
                    name = "?"
                found.append((int(entry.name), name))
                break
    return found


class PortLike(Protocol):
    """What the client needs of a port: a real one (:class:`Port`) or an in-process emulated OP2's
    (:class:`~op2motion.bus.emulator.lockstep.LockstepPort`). ``read`` takes a deadline on ``clock``."""

    path: str
    clock: Clock
    latency_timer_ms: int | None
    low_latency: str

    def write(self, data: bytes) -> None: ...

    def read(self, deadline: float) -> bytes: ...

    def flush_input(self) -> bytes: ...

    def close(self) -> None: ...


class Port:
    """An open serial port: raw, exclusive, every call bounded by a deadline."""

    clock: Clock = REAL

    def __init__(self, path: str, serial: Any, latency_timer_ms: int | None = None, low_latency: str = ""):
        self.path, self.serial = path, serial
        self.fd: int = serial.fileno()
        self.latency_timer_ms, self.low_latency = latency_timer_ms, low_latency

    def write(self, data: bytes) -> None:
        """Send ``data`` within :data:`WRITE_TIMEOUT_S`."""
        deadline = time.monotonic() + WRITE_TIMEOUT_S
        view = memoryview(data)
        while view:
            try:
                sent = os.write(self.fd, view)
                view = view[sent:]
            except BlockingIOError:
                pass
            except OSError as exc:
                raise PortFailed(f"writing to {self.path} failed: {exc.strerror or exc}", PARAM) from None
            if view:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise PortFailed(f"{self.path} did not take {len(data)} bytes within "
                                     f"{WRITE_TIMEOUT_S * 1000:.0f} ms", PARAM)
                select.select([], [self.fd], [], left)

    def read(self, deadline: float) -> bytes:
        """What arrives before ``deadline`` (time.monotonic) — at least one chunk if any came, else ``b""``."""
        left = deadline - time.monotonic()
        try:
            ready, _, _ = select.select([self.fd], [], [], max(left, 0.0))
            if not ready:
                return b""
            return os.read(self.fd, READ_CHUNK)
        except BlockingIOError:
            return b""
        except InterruptedError:
            return b""
        except OSError as exc:
            raise PortFailed(f"reading from {self.path} failed: {exc.strerror or exc}", PARAM) from None

    def flush_input(self) -> bytes:
        """Take whatever waits to be read (late replies of an earlier request) and return it, for the caller to
        count and drop."""
        held = bytearray()
        for _ in range(64):
            try:
                chunk = os.read(self.fd, READ_CHUNK)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:
                raise PortFailed(f"reading from {self.path} failed: {exc.strerror or exc}", PARAM) from None
            if not chunk:
                break
            held += chunk
        return bytes(held)

    def close(self) -> None:
        """Release the port (and its lock)."""
        with contextlib.suppress(Exception):
            self.serial.close()

    def __enter__(self) -> "Port":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_port(path: str, baud: int = BAUD) -> Port:
    """Open the robot's serial port (see the module docstring); every refusal is an :class:`InputError` naming the
    ``port`` parameter."""
    import fcntl
    import termios

    import serial

    device = _check_device(path)
    ser = serial.Serial()
    ser.port, ser.baudrate, ser.timeout, ser.write_timeout = path, baud, 0, WRITE_TIMEOUT_S
    try:
        ser.open()
    except (serial.SerialException, OSError, ValueError) as exc:
        raise InputError(f"cannot open {path}: {exc}", PARAM) from None
    try:
        if not os.isatty(ser.fileno()):
            raise InputError(f"expected a serial device, got a character device that is not a terminal: {path}",
                             PARAM)
        try:
            fcntl.flock(ser.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                raise InputError(f"busy: another op2motion holds {path}", PARAM) from None
            raise InputError(f"cannot lock {path}: {exc.strerror or exc}", PARAM) from None
        if not is_pseudo_terminal(device):
            others = holders(device)
            if others:
                pid, name = others[0]
                raise InputError(f"busy: process {pid} ({name}) holds {path}; stop it first (the stock framework "
                                 f"must not hold the port at the same time)", PARAM)
            with contextlib.suppress(OSError):
                fcntl.ioctl(ser.fileno(), termios.TIOCEXCL)
        timer, how = (None, "not a USB serial adapter (a pseudo-terminal)") if is_pseudo_terminal(device) else \
            low_latency(ser, path)
    except BaseException:
        ser.close()
        raise
    port = Port(path, ser, timer, how)
    port.flush_input()
    return port


def low_latency(ser: Any, path: str) -> tuple[int | None, str]:
    """Ask the driver for low latency (``ASYNC_LOW_LATENCY``: ftdi_sio then sets the latency timer to 1 ms) and,
    where sysfs shows the timer and it is still above 1 ms, write 1 into it; (the timer read back [ms] or None where
    there is none to read, what happened in words)."""
    said = []
    try:
        ser.set_low_latency_mode(True)
        said.append("ASYNC_LOW_LATENCY set")
    except (OSError, ValueError, AttributeError, NotImplementedError) as exc:
        said.append(f"ASYNC_LOW_LATENCY refused ({getattr(exc, 'strerror', None) or exc})")
    sysfs = Path(sysfs_timer_path(path))
    timer = _read_timer(sysfs)
    if timer is not None and timer > 1:
        try:
            sysfs.write_text("1")
            said.append(f"wrote 1 to {sysfs}")
        except OSError as exc:
            said.append(f"could not write {sysfs} ({exc.strerror or exc})")
        timer = _read_timer(sysfs)
    return timer, "; ".join(said)


def _read_timer(sysfs: Path) -> int | None:
    try:
        return int(sysfs.read_text().strip())
    except (OSError, ValueError):
        return None
