"""The robot's serial port, opened safely, with bounded timeouts everywhere.

:func:`open_port` refuses, as bad input naming ``--port`` (exit 2), a path that does not exist, that is not a
character device, whose device is not a terminal (checked against ``/proc/devices`` *before* opening: opening some
character devices, a watchdog for one, has effects), and a port another process holds open (:func:`holders`: a scan of
every process's open files for the same device, named by process ID and command name; the stock framework takes no
lock), unless asked to share it (``shared``: ``--shared-port``, for a socat bridge that keeps the terminal side of its
pseudo-terminal open itself); then it takes an advisory lock (``flock``: two op2motion runs never share a port) and,
on a real serial device, ``TIOCEXCL`` so that nobody else opens it while we drive the robot. A pseudo-terminal's
*other* side (its master: an emulator's, a bridge's) is not the port but the far end of its wire: whoever holds only
that is not holding the port. A pseudo-terminal is not made exclusive: ``TIOCEXCL`` would outlive our close (the
terminal lives on while its master is open) and refuse the next program. The port runs at 1 Mbps, raw. A USB serial
adapter's latency timer is set to 1 ms (:func:`low_latency`: ``ASYNC_LOW_LATENCY``, and the ``latency_timer`` file in
sysfs where the driver has one and we may write it) and read back, so that what was achieved is known
(:attr:`Port.latency_timer_ms`, :attr:`Port.low_latency`) rather than hoped for; a pseudo-terminal has none.

:class:`Port` reads and writes with deadlines (``select``): nothing here blocks forever. Every failure of the port, at
open or mid-run (the USB cable pulled: a zero-length read from a terminal that said it was readable is its hang-up;
an I/O error, a terminal (``termios``) error, a device gone), raises :class:`~op2motion.errors.PortFailed` naming the
port (a check that ran and failed: exit 1); the 8 ms loop ends the run on it as a fault of its own (:mod:`.loop`).
Paths are quoted in messages with :func:`~op2motion.errors.shown` (a path with a newline stays on one line).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import select
import stat
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from op2motion.bus.clock import REAL, Clock
from op2motion.errors import InputError, Op2MotionError, PortFailed, one_line, ref, shown

BAUD = 1_000_000                   # the OP2's bus: Dynamixel baud number 1
WRITE_TIMEOUT_S = 0.05             # a write that cannot go out in this long means the port is stuck
READ_CHUNK = 4096
TTY_DRIVERS = ("tty", "pts", "ttyS", "ttyUSB", "ttyACM", "ttyAMA", "usb/tty", "/dev/tty")
PARAM = "port"
SHARED = "shared_port"             # the option that opens a port other processes hold (``--shared-port``)
UNPLUGGED = " (the USB cable unplugged, the robot switched off, or the bridge serving it ended?)"
SYSFS_TIMER = "/sys/bus/usb-serial/devices/{name}/latency_timer"


@dataclass(frozen=True)
class PortRequest:
    """A serial port to open by its ``path``, and how: ``shared`` opens it although other processes hold it open (the
    bridge that serves it: socat keeps its pseudo-terminal's terminal side open itself; see :func:`open_port`)."""

    path: str
    shared: bool = False


@functools.cache
def port_errors() -> tuple[type[BaseException], ...]:
    """What a failing port raises: ``OSError`` (EIO, a device gone), ``termios.error`` (not an ``OSError``: from
    pyserial's ``tcsetattr``/``tcflush``), pyserial's ``SerialException``, ``ValueError`` (a closed descriptor)."""
    import termios

    import serial

    return OSError, ValueError, termios.error, serial.SerialException


def _errno(exc: BaseException) -> int | None:
    """The error number of a port error (``termios.error`` carries it as its first argument)."""
    code = getattr(exc, "errno", None)
    if code is None and exc.args and isinstance(exc.args[0], int):
        code = exc.args[0]
    return code if isinstance(code, int) else None


def _why(exc: BaseException) -> str:
    """A port error in words, without the path it may repeat unquoted (pyserial's messages do)."""
    code = _errno(exc)
    if code is not None:
        return os.strerror(code)
    return one_line(str(exc)) or type(exc).__name__


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
        got = repr(path) if path else "an empty string"
        raise InputError(f"expected the robot's serial port (e.g. /dev/ttyUSB0), got {got}", PARAM)
    where = shown(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"no such serial port: {where} (is the robot's USB cable plugged in and the robot on?)",
                         PARAM) from None
    except PermissionError:
        raise InputError(f"permission denied: {where} (add yourself to the 'dialout' group)", PARAM) from None
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot use {where}: {_why(exc)}", PARAM) from None
    if not stat.S_ISCHR(st.st_mode):
        kind = "directory" if stat.S_ISDIR(st.st_mode) else "regular file" if stat.S_ISREG(st.st_mode) else \
            "block device" if stat.S_ISBLK(st.st_mode) else "socket or pipe"
        raise InputError(f"expected a serial device, got a {kind}: {where}", PARAM)
    drivers = _drivers()
    if drivers is not None and not _is_tty(drivers.get(os.major(st.st_rdev), set())):
        raise InputError(f"expected a serial device, got another kind of character device: {where}", PARAM)
    return st


def same_port(held: os.stat_result, device: os.stat_result, pseudo: bool) -> bool:
    """Whether an open file (``held``, its stat) is the port ``device``: the same character device (``st_rdev``:
    whatever node or link it was opened by) and, for a pseudo-terminal, the same inode of the same ``devpts``
    (another devpts instance, a container's, numbers its terminals from 0 again). A pseudo-terminal's master side
    (``/dev/ptmx``) is another device: the far end of the wire, not the port."""
    if not stat.S_ISCHR(held.st_mode) or held.st_rdev != device.st_rdev:
        return False
    return not pseudo or (held.st_dev, held.st_ino) == (device.st_dev, device.st_ino)


def holders(device: os.stat_result, skip: int | None = None) -> list[tuple[int, str]]:
    """Other processes (not ``skip``, default this one) with the port ``device`` open (:func:`same_port`):
    (pid, command name), as far as ``/proc`` shows (processes of other users may be hidden)."""
    found = []
    skip = os.getpid() if skip is None else skip
    pseudo = is_pseudo_terminal(device)
    for entry in Path("/proc").iterdir() if Path("/proc").is_dir() else ():
        if not entry.name.isdigit() or int(entry.name) == skip:
            continue
        try:
            fds = list((entry / "fd").iterdir())
        except OSError:
            continue
        for fd in fds:
            try:
                held = os.stat(fd)
            except OSError:
                continue
            if same_port(held, device, pseudo):
                try:
                    name = (entry / "comm").read_text().strip()
                except OSError:
                    name = "?"
                found.append((int(entry.name), one_line(name)))
                break
    return found


def _named(others: list[tuple[int, str]]) -> str:
    """``process 4242 (socat)``, ``and 2 more`` after the first."""
    pid, name = others[0]
    return f"process {pid} ({name})" + (f" and {len(others) - 1} more" if len(others) > 1 else "")


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


#: Where a robot is: a port's path (``/dev/ttyUSB0``, or ``lockstep[:...]``: an emulated OP2 in this process), a path
#: with how to open it (:class:`PortRequest`), or a port already open.
RobotPort = str | PortRequest | PortLike


class Port:
    """An open serial port: raw, exclusive, every call bounded by a deadline; any failure is :class:`PortFailed`."""

    clock: Clock = REAL

    def __init__(self, path: str, serial: Any, latency_timer_ms: int | None = None, low_latency: str = ""):
        self.path, self.serial = path, serial
        self.fd: int = serial.fileno()
        self.latency_timer_ms, self.low_latency = latency_timer_ms, low_latency

    def _failed(self, doing: str, exc: BaseException) -> PortFailed:
        return PortFailed(f"{doing} {shown(self.path)} failed: {_why(exc)}{UNPLUGGED}", PARAM)

    def _hung_up(self) -> PortFailed:
        return PortFailed(f"{shown(self.path)} hung up (it reads as ready, with nothing in it){UNPLUGGED}", PARAM)

    def write(self, data: bytes) -> None:
        """Send ``data`` within :data:`WRITE_TIMEOUT_S`."""
        deadline = time.monotonic() + WRITE_TIMEOUT_S
        view = memoryview(data)
        while view:
            try:
                with contextlib.suppress(BlockingIOError):     # the adapter's buffer is full: wait below
                    view = view[os.write(self.fd, view):]
                left = deadline - time.monotonic()
                if view and left <= 0:
                    raise PortFailed(f"{shown(self.path)} did not take {len(data)} bytes within "
                                     f"{WRITE_TIMEOUT_S * 1000:.0f} ms", PARAM)
                if view:
                    select.select([], [self.fd], [], left)
            except port_errors() as exc:
                raise self._failed("writing to", exc) from None

    def read(self, deadline: float) -> bytes:
        """What arrives before ``deadline`` (time.monotonic) — at least one chunk if any came, else ``b""``.

        A terminal that is ready to be read yet gives nothing has hung up (its other side closed, the USB adapter
        unplugged): raw with VMIN 0 a terminal with nothing in it reads as empty too, but is never ready; asked twice
        so that bytes another reader took in between are not taken for a hang-up."""
        wait = max(deadline - time.monotonic(), 0.0)
        try:
            for _ in range(2):
                ready, _, _ = select.select([self.fd], [], [], wait)
                if not ready:
                    return b""
                data = os.read(self.fd, READ_CHUNK)
                if data:
                    return data
                wait = 0.0
        except (BlockingIOError, InterruptedError):
            return b""
        except port_errors() as exc:
            raise self._failed("reading from", exc) from None
        raise self._hung_up()

    def flush_input(self) -> bytes:
        """Take whatever waits to be read (late replies of an earlier request) and return it, for the caller to
        count and drop."""
        held = bytearray()
        for _ in range(64):
            chunk = self.read(0.0)
            if not chunk:
                break
            held += chunk
        return bytes(held)

    def close(self) -> None:
        """Release the port (and its lock); a port that failed closes quietly."""
        with contextlib.suppress(Exception):
            self.serial.close()

    def __enter__(self) -> "Port":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_port(path: str, baud: int = BAUD, shared: bool = False) -> Port:
    """Open the robot's serial port (see the module docstring): a refusal is an :class:`InputError` naming the
    ``port`` parameter (exit 2), a port that fails as it opens :class:`PortFailed` (exit 1). ``shared``: open it
    even though other processes hold it open (a bridge's)."""
    import serial

    device = _check_device(path)
    ser = serial.Serial()
    ser.port, ser.baudrate, ser.timeout, ser.write_timeout = path, baud, 0, WRITE_TIMEOUT_S
    try:
        ser.open()
    except port_errors() as exc:
        raise _open_failed(path, device, exc) from None
    try:
        _claim(ser.fileno(), path, device, shared)
        timer, how = (None, "not a USB serial adapter (a pseudo-terminal)") if is_pseudo_terminal(device) else \
            low_latency(ser, path)
        os.set_blocking(ser.fileno(), False)        # no write waits in the kernel: each waits in select, bounded
        port = Port(path, ser, timer, how)
        port.flush_input()
    except BaseException as exc:
        with contextlib.suppress(Exception):
            ser.close()
        if isinstance(exc, port_errors()):
            raise PortFailed(f"setting up {shown(path)} failed: {_why(exc)}{UNPLUGGED}", PARAM) from None
        raise
    return port


def _open_failed(path: str, device: os.stat_result, exc: BaseException) -> Op2MotionError:
    """What a failed open means: busy (held exclusively), permission, the device failing (exit 1), else bad input."""
    code, where = _errno(exc), shown(path)
    if code == errno.EBUSY:
        others = holders(device)
        who = _named(others) if others else "another program"
        return InputError(f"busy: {who} holds {where} exclusively; stop it first", PARAM)
    if code in (errno.EACCES, errno.EPERM):
        return InputError(f"permission denied: {where} (add yourself to the 'dialout' group)", PARAM)
    if code in (errno.EIO, errno.ENXIO, errno.ENODEV) or not isinstance(exc, OSError):
        return PortFailed(f"opening {where} failed: {_why(exc)}{UNPLUGGED}", PARAM)
    return InputError(f"cannot open {where}: {_why(exc)}", PARAM)


def _claim(fd: int, path: str, device: os.stat_result, shared: bool) -> None:
    """Refuse a port that is not a terminal, or that another process holds (named; unless ``shared``); take the
    advisory lock and, on a real serial device, ``TIOCEXCL`` (see the module docstring)."""
    import fcntl
    import termios

    where = shown(path)
    if not os.isatty(fd):
        raise InputError(f"expected a serial device, got a character device that is not a terminal: {where}", PARAM)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
            others = holders(device)
            raise InputError(f"busy: another op2motion{' (' + _named(others) + ')' if others else ''} holds "
                             f"{where}", PARAM) from None
        raise InputError(f"cannot lock {where}: {_why(exc)}", PARAM) from None
    others = [] if shared else holders(device)
    if others:
        raise InputError(f"busy: {_named(others)} holds {where} open; stop it first (the stock framework must "
                         f"not hold the port at the same time), or, if it is the bridge that serves this port "
                         f"(socat, ser2net), pass {ref(SHARED)}", PARAM)
    if not is_pseudo_terminal(device):
        with contextlib.suppress(OSError):
            fcntl.ioctl(fd, termios.TIOCEXCL)


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
