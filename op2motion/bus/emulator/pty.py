"""The emulated OP2's pseudo-terminal (:class:`PtyServing`, a part of :class:`.server.Emulator`): the terminal made
and linked where the robot's port would be, and the one thread that serves it in real time.

:meth:`PtyServing.open` makes a pseudo-terminal and a symbolic link to its terminal side at the path asked for
(pyserial and dynamixel-sdk open it like the real port). :meth:`PtyServing.serve` takes the host's bytes as they
arrive and hands them to the emulator (:meth:`.server.Emulator.receive`), and advances the body and the wire
(:meth:`.server.Emulator.advance`) in batches of at most :data:`BATCH_STEPS` physics steps, kept on the wall clock. If
the machine cannot keep up, simulated time slips behind the wall clock rather than running in bursts (``slipped_s``).
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import threading
import time
import tty
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from op2motion.bus.realtime import EMULATOR_PRIORITY, realtime, steady
from op2motion.errors import InputError

if TYPE_CHECKING:
    from op2motion.bus.emulator.body import EmulatedBody
    from op2motion.bus.emulator.timing import TimedLink
    from op2motion.bus.emulator.wire import Wire

BATCH_STEPS = 4                    # physics steps between two looks at the port
MAX_BEHIND_S = 0.05                # further behind the wall clock than this, simulated time slips instead
HANGUP_SLEEP_S = 0.002             # with no program on the port, look again this often


class PtyServing:
    """The pseudo-terminal side of an emulator (see the module docstring); the emulator provides the rest."""

    master: int | None
    link: Path | None
    pty_name: str
    slipped_s: float
    outbox: bytearray
    body: EmulatedBody
    wire: Wire
    timed_wire: TimedLink
    _stop: threading.Event
    _thread: threading.Thread | None
    #: The emulator's: its simulated time [s]; the host's bytes at a simulated time; the body and the wire up to one.
    _now: Callable[[], float]
    receive: Callable[[float, bytes], None]
    advance: Callable[[float], None]

    def open(self, link: str | Path) -> str:
        """Make the pseudo-terminal and the link to it at ``link``; returns the terminal's own path."""
        link = Path(link)
        if link.is_symlink():
            target = os.readlink(link)
            if target.startswith("/dev/pts/") or not os.path.exists(link):
                link.unlink()                     # a stale link of an earlier emulator
        if os.path.lexists(link):
            raise InputError(f"{link} exists and is not an emulator's link (expected a free path for the link)",
                             "link")
        if not link.parent.is_dir():
            raise InputError(f"expected the link in an existing folder, got {link}", "link")
        master, slave = os.openpty()
        tty.setraw(slave)
        self.pty_name = os.ttyname(slave)
        os.close(slave)                           # the terminal side is the client's: only it holds it open
        os.set_blocking(master, False)
        self.master = master
        os.symlink(self.pty_name, link)
        self.link = link
        return self.pty_name

    def _close_pty(self) -> None:
        """Remove the link (if it is still this terminal's) and close the pseudo-terminal."""
        if self.link is not None:
            with contextlib.suppress(OSError):
                if os.readlink(self.link) == self.pty_name:
                    self.link.unlink()
            self.link = None
        if self.master is not None:
            with contextlib.suppress(OSError):
                os.close(self.master)
            self.master = None

    def start(self) -> None:
        """Serve in a background thread (for use from Python; ``robot emulate`` serves in the foreground)."""
        self._stop.clear()
        self._thread = threading.Thread(target=self.serve, name="op2-emulator", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Ask the serving loop to end, and wait for its thread."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
            self._thread = None

    def serve(self, stop: threading.Event | None = None) -> None:
        """Answer packets and step the body in real time until ``stop`` (or :meth:`stop`) is set (at real-time
        priority where the system allows it: :mod:`..realtime`)."""
        if self.master is None:
            raise InputError("expected open() before serve(): the emulator has no pseudo-terminal yet", "emulator")
        with steady(), realtime(EMULATOR_PRIORITY):
            self._serve(stop or self._stop)

    def _master_fd(self) -> int:
        """The pseudo-terminal's master side (after :meth:`open`)."""
        if self.master is None:
            raise InputError("expected open() before serve(): the emulator has no pseudo-terminal yet", "emulator")
        return self.master

    def _serve(self, stop: threading.Event) -> None:
        """Simulated time kept on the wall clock (``t0``: the wall time of simulated 0, moved on when the machine
        falls behind by more than :data:`MAX_BEHIND_S`)."""
        master = self._master_fd()
        t0 = time.monotonic() - self._now()
        while not stop.is_set() and not self._stop.is_set():
            event = self.timed_wire.next_event()
            due = self._now() + BATCH_STEPS * self.body.dt
            due = due if event is None else min(due, event)
            wait = max(0.0, t0 + due - time.monotonic())
            ready, _, _ = select.select([master], [], [], wait)
            if ready and not self._receive(time.monotonic() - t0):           # no program holds the port
                time.sleep(min(wait, HANGUP_SLEEP_S))
            behind = time.monotonic() - t0 - self._now()
            if behind > MAX_BEHIND_S:
                self.slipped_s += behind - MAX_BEHIND_S
                t0 += behind - MAX_BEHIND_S
            self.advance(time.monotonic() - t0)
            self._flush(master)

    def _flush(self, master: int) -> None:
        """Hand the host what the wire delivered."""
        if self.outbox:
            with contextlib.suppress(BlockingIOError, OSError):
                os.write(master, bytes(self.outbox))
            self.outbox.clear()

    def _receive(self, t: float) -> bool:
        """Read what the host wrote (at simulated time ``t``); False when no program holds the port."""
        master = self._master_fd()
        try:
            data = os.read(master, 4096)
        except BlockingIOError:
            return True
        except OSError as exc:
            if exc.errno == errno.EIO:                              # the client closed the port
                self.wire.parser.clear()
                return False
            raise
        if data:
            self.receive(max(t, self._now()), data)
        return True
