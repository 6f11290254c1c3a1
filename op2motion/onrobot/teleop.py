"""Steering a walk from the keyboard (``op2motion robot walk --teleop``): keys change the command a steered walk
(:class:`~op2motion.gait.steer.SteerableWalk`) takes from its next step.

Keys (:data:`HELP`): ``w``/``s`` (or the up/down arrows) faster forward/backward by :data:`VX_STEP_M_S`, ``a``/``d``
sideways left/right by :data:`VY_STEP_M_S`, ``q``/``e`` (or the left/right arrows) turn left/right by
:data:`YAW_STEP_RAD_S`, space stands (a zero command: the walk slows down and closes its feet), ``z``/``c`` kick with
the left/right foot (stop, kick, walk on), ``x`` ends the walk (it stops within two steps, on both feet, and the
command exits 0 once the robot stands still). Ctrl-C stops as it does for every walk. The keys add up what they ask,
each axis within its own limit, and the walk is told that within its measured envelope
(:mod:`op2motion.gait.envelope`): holding a key cannot ask for more, and a key and its opposite cancel exactly.
The command line reads keys only from a terminal (``robot walk --teleop``).

Keys arrive on another thread (:func:`read_keys`); the loop applies them between ticks (:meth:`Teleop.apply`), so the
walk's planner only ever runs on the loop's thread.
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import threading
from typing import Any, Callable, Iterator

VX_STEP_M_S = 0.05                      # one w/s press [m/s]
VY_STEP_M_S = 0.02                      # one a/d press [m/s]
YAW_STEP_RAD_S = math.radians(5.0)      # one q/e press [rad/s]
POLL_S = 0.1                            # the key reader looks for a stop this often [s]
ZERO = 1e-9                             # a command component this small is a zero left by rounding [m/s, rad/s]
ARROWS = {"\x1b[A": "w", "\x1b[B": "s", "\x1b[C": "e", "\x1b[D": "q"}
HELP = ("keys: w/s (up/down) forward/backward, a/d sideways, q/e (left/right) turn, space stand, z/c kick left/right, "
        "x end the walk, Ctrl-C stop")


class Teleop:
    """The command the keys have built, kept within ``envelope`` (an :class:`~op2motion.gait.envelope.Envelope`),
    and what is still to be told to the walk. Thread-safe: :meth:`feed` on the key thread, :meth:`apply` on the
    loop's."""

    def __init__(self, envelope: Any, on_change: Callable[[str], None] | None = None):
        self.envelope, self.on_change = envelope, on_change
        self.command = (0.0, 0.0, 0.0)
        self.wanted = (0.0, 0.0, 0.0)       # the keys' sum, each axis within its own limit (command: the envelope's)
        self.ended = False
        self.pending: list[tuple[str, Any]] = []
        self.keys = 0
        self._lock = threading.Lock()
        self._escape = ""

    def feed(self, text: str) -> None:
        """Keys as typed (arrows as their escape sequences); unknown keys are ignored."""
        for char in text:
            if self._escape or char == "\x1b":
                self._escape += char
                if len(self._escape) < 3:
                    continue
                char, self._escape = ARROWS.get(self._escape, ""), ""
            self._key(char.lower())

    def _key(self, key: str) -> None:
        steps = {"w": (VX_STEP_M_S, 0.0, 0.0), "s": (-VX_STEP_M_S, 0.0, 0.0), "a": (0.0, VY_STEP_M_S, 0.0),
                 "d": (0.0, -VY_STEP_M_S, 0.0), "q": (0.0, 0.0, YAW_STEP_RAD_S), "e": (0.0, 0.0, -YAW_STEP_RAD_S)}
        with self._lock:
            if self.ended:
                return
            if key in steps:
                # keys add to what was asked, not to the envelope's scaled command: a then d is back where it was
                # (adding to a command scaled down for a combined walk left vy at -0.002 m/s: a slow sideways drift)
                self.wanted = tuple(self._alone(axis, c + d)  # type: ignore[assignment]
                                    for axis, (c, d) in enumerate(zip(self.wanted, steps[key])))
                self.command = _exact(self.envelope.clamp(*self.wanted))  # type: ignore[assignment]
                self.pending.append(("command", self.command))
            elif key == " ":
                self.command = self.wanted = (0.0, 0.0, 0.0)
                self.pending.append(("command", self.command))
            elif key in ("z", "c"):
                self.pending.append(("kick", "left" if key == "z" else "right"))
            elif key == "x":
                self.ended = True
                self.pending.append(("stop", None))
            else:
                return
            self.keys += 1
        if self.on_change is not None:
            self.on_change(self.describe())

    def _alone(self, axis: int, value: float) -> float:
        """``value`` on ``axis`` (0 vx, 1 vy, 2 yaw rate) within the envelope's limit for that axis alone."""
        command = [0.0, 0.0, 0.0]
        command[axis] = value
        return _exact((self.envelope.clamp(*command)[axis],))[0]

    def apply(self, walk: Any) -> None:
        """Tell ``walk`` (a steered walk) what the keys asked since the last call, in order."""
        with self._lock:
            pending, self.pending = self.pending, []
        for kind, value in pending:
            if kind == "command":
                walk.command(*value)
            elif kind == "kick":
                walk.kick(value)
            else:
                walk.stop()

    def describe(self) -> str:
        """The command for people: vx, vy [m/s], yaw rate [deg/s]."""
        vx, vy, yaw = self.command
        state = "ending" if self.ended else "walking"
        return (f"{state}: vx {signed_text(vx, 2)} m/s, vy {signed_text(vy, 2)} m/s, "
                f"turn {signed_text(math.degrees(yaw), 0)} °/s")


def _exact(values: Any) -> tuple[float, ...]:
    """``values`` as floats, a residue of steps that cancel (0.05 * 3 - 0.05 * 3) an exact zero."""
    return tuple(0.0 if abs(v) < ZERO else float(v) for v in values)


def signed_text(value: float, digits: int) -> str:
    """``value`` with its sign and ``digits`` decimals, never a negative zero (a command whose keys cancelled to
    -1e-17, or a heading of -0.01° shown to a degree, reads ``+0``)."""
    return f"{round(value, digits) + 0.0:+.{digits}f}"


@contextlib.contextmanager
def read_keys(fd: int, teleop: Teleop) -> Iterator[threading.Thread]:
    """Read keys from ``fd`` (a terminal: switched to single keys without echo for the while, restored after; a pipe:
    read as it comes) into ``teleop`` on a thread, for the ``with`` block (or until the input ends)."""
    stop = threading.Event()
    saved: Any = None
    if os.isatty(fd):
        import termios
        import tty

        saved = termios.tcgetattr(fd)
        tty.setcbreak(fd)

    def restore() -> None:
        if saved is not None:
            import termios

            termios.tcsetattr(fd, termios.TCSADRAIN, saved)

    def pump() -> None:
        while not stop.is_set():
            ready, _, _ = select.select([fd], [], [], POLL_S)
            if not ready:
                continue
            data = os.read(fd, 64)
            if not data:
                return
            teleop.feed(data.decode("utf-8", "replace"))

    thread = threading.Thread(target=pump, name="op2motion-keys", daemon=True)
    thread.start()
    try:
        yield thread
    finally:
        stop.set()
        thread.join(POLL_S * 3)
        restore()
