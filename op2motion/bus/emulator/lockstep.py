"""An emulated OP2 in this process, in lockstep: a port (:class:`LockstepPort`, what
:func:`~op2motion.bus.port.open_port` gives for a real robot) whose clock is the emulator's simulated time
(:class:`~op2motion.bus.clock.LockstepClock`).

The client writes a request: the emulator takes it at the clock's time; the client waits for replies: the clock moves
to the moment the wire model (:mod:`.timing`) delivers the next USB packet, or to the client's deadline, and the
body's physics steps up to it on the way. The 8 ms loop's sleeps move the clock too. So the client, the wire and the
body advance together, deterministically, as fast as the machine computes them; the bytes and their times are the
ones the real-time emulator on a pseudo-terminal would give. :func:`lockstep_robot` makes one from a short text
(``op2motion robot ... --port lockstep:...``), so that the robot commands run against it as they run on a robot.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from op2motion.bus.clock import Clock, LockstepClock
from op2motion.bus.emulator.faults import ALL_ERRORS, Faults, parse_pair, parse_timed, with_board
from op2motion.bus.emulator.timing import INSTANT, KERNEL_LATENCY_TIMER_MS, WireTiming
from op2motion.errors import InputError
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.bus.emulator.server import Emulator
    from op2motion.physics import EngineName

PREFIX = "lockstep"
MAX_PACE = 100.0                   # simulated seconds a wall second, at most
PARAM = "port"


class LockstepPort:
    """The host's end of an in-process emulated OP2 (see the module docstring); the interface of
    :class:`~op2motion.bus.port.Port`. ``pace``: at most that many simulated seconds a wall second (None: as fast as
    it computes)."""

    def __init__(self, emulator: Emulator, path: str = PREFIX, pace: float | None = None):
        self.emulator, self.path = emulator, path
        self.steps = LockstepClock(emulator.sim_time(), pace)
        self.clock: Clock = self.steps
        self.steps.listen(emulator.advance)
        self.latency_timer_ms: int | None = None      # not a USB adapter: nothing to read or set
        self.low_latency: str = "not a USB serial adapter (the emulated wire's timer is fixed)"
        self.closed = False

    def write(self, data: bytes) -> None:
        """Send ``data`` now."""
        self._check_open()
        self.emulator.receive(self.clock.now(), bytes(data))

    def read(self, deadline: float) -> bytes:
        """What arrives before ``deadline`` [s, this port's clock]: the next USB packet(s), else ``b""`` once the
        clock reached the deadline."""
        self._check_open()
        box = self.emulator.outbox
        while not box:
            event = self.emulator.timed_wire.next_event()
            if event is None or event > deadline:
                self.clock.sleep_until(deadline)
                break
            self.clock.sleep_until(max(event, self.clock.now()))
            if event <= self.clock.now() and not box:
                self.emulator.advance(self.clock.now())         # an event at this very time
        data = bytes(box)
        box.clear()
        return data

    def flush_input(self) -> bytes:
        """Throw away (and return) what waits to be read."""
        self.emulator.advance(self.clock.now())
        data = bytes(self.emulator.outbox)
        self.emulator.outbox.clear()
        return data

    def close(self) -> None:
        """Nothing to release (the emulator is the caller's)."""
        self.closed = True

    def _check_open(self) -> None:
        if self.closed:
            raise InputError("expected an open port, got one already closed", PARAM)

    def __enter__(self) -> "LockstepPort":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass(frozen=True)
class LockstepSetup:
    """What a ``lockstep:`` port text asks for: the engine, the start, the wire, the servos' return delay, the
    faults (the board it plays among them: the model number of ID 200), the pace (simulated seconds a wall second
    at most; None: as fast as it computes) and whether it starts cold."""

    engine: EngineName = "mujoco"
    start: str = "standing"
    timing: WireTiming = WireTiming()
    return_delay: int | None = None
    faults: Faults = field(default_factory=Faults)
    pace: float | None = None
    cold: bool = False


def is_lockstep(port: str) -> bool:
    """Whether a ``--port`` text names an in-process emulated OP2."""
    return port == PREFIX or port.startswith(PREFIX + ":")


def parse_lockstep(text: str) -> LockstepSetup:
    """``lockstep[:key=value,...]`` with keys ``engine`` (mujoco, pybullet), ``start`` (standing, lying_front, ...),
    ``wire`` (real, instant), ``latency-timer-ms`` (1..255), ``return-delay`` (0..254, 2 µs units), ``lose``,
    ``corrupt`` (shares), ``seed``, ``missing`` (IDs joined by +), ``unplug`` / ``overheat`` / ``push``
    (``ID@S[:C]`` joined by +), ``supply`` [V], ``cold`` (1: just switched on, the servos unpowered), ``pace``
    (simulated seconds a wall second at most, e.g. 1 to steer a walk by keys; default as fast as it computes),
    ``horn`` (``ID:TICKS`` joined by +: a servo's horn mounted off), ``board`` (cm730, cm740), ``model``
    (``ID:NUMBER`` joined by +: devices reporting another model, e.g. 14:12)
    and ``errors`` (``ID:BITS`` joined by +: devices reporting these error bits, e.g. 14:all or 14:0x24)."""
    from op2motion.bus.emulator.body import STARTS
    from op2motion.physics import ENGINES

    fields: dict[str, str] = {}
    rest = text[len(PREFIX) + 1:] if text.startswith(PREFIX + ":") else ""
    for item in filter(None, rest.split(",")):
        key, sep, value = item.partition("=")
        if not sep or not value:
            raise InputError(f"expected key=value items after 'lockstep:', got {item!r}", PARAM)
        fields[key.strip()] = value.strip()
    known = {"engine", "start", "wire", "latency-timer-ms", "return-delay", "lose", "corrupt", "seed", "missing",
             "unplug", "overheat", "push", "supply", "pace", "cold", "board", "model", "errors", "horn"}
    unknown = sorted(set(fields) - known)
    if unknown:
        raise InputError(f"expected lockstep keys among {', '.join(sorted(known))}, got {unknown[0]!r}", PARAM)
    engine, start = fields.get("engine", "mujoco"), fields.get("start", "standing")
    if engine not in ENGINES or start not in STARTS:
        raise InputError(f"expected engine mujoco or pybullet and start one of {', '.join(STARTS)}, got {engine!r}, "
                         f"{start!r}", PARAM)
    pace = _number(fields, "pace", 0.0)
    if not 0.0 <= pace <= MAX_PACE:
        raise InputError(f"expected a pace of 0 (as fast as it computes) to {MAX_PACE:g}, got {fields['pace']!r}",
                         PARAM)
    return LockstepSetup(engine, start, _timing(fields), _whole(fields, "return-delay", 0, 254),
                         _faults(fields), pace or None, bool(_whole(fields, "cold", 0, 1)))


def _number(fields: dict[str, str], key: str, default: float) -> float:
    try:
        return float(fields[key]) if key in fields else default
    except ValueError:
        raise InputError(f"expected a number for lockstep key {key}, got {fields[key]!r}", PARAM) from None


def _whole(fields: dict[str, str], key: str, low: int, high: int) -> int | None:
    if key not in fields:
        return None
    value = _number(fields, key, 0.0)
    if value != int(value) or not low <= value <= high:
        raise InputError(f"expected a whole number {low}..{high} for lockstep key {key}, got {fields[key]!r}", PARAM)
    return int(value)


def _timing(fields: dict[str, str]) -> WireTiming:
    wire = fields.get("wire", "real")
    if wire not in ("real", "instant"):
        raise InputError(f"expected wire=real or wire=instant, got {wire!r}", PARAM)
    if wire == "instant":
        return INSTANT
    timer = _whole(fields, "latency-timer-ms", 1, 255)
    return WireTiming(latency_timer_s=(timer if timer is not None else 1) / 1000.0)


def _faults(fields: dict[str, str]) -> Faults:
    def items(key: str) -> list[str]:
        return [v for v in fields.get(key, "").split("+") if v]

    missing = set()
    for value in items("missing"):
        if not value.isdigit():
            raise InputError(f"expected servo IDs joined by + for lockstep key missing, got {value!r}", PARAM)
        missing.add(int(value))
    horn = {}
    for value in items("horn"):
        device, _, ticks = value.partition(":")
        if not device.isdigit() or not ticks.lstrip("+-").isdigit():
            raise InputError(f"expected ID:TICKS joined by + for lockstep key horn, got {value!r}", PARAM)
        horn[int(device)] = int(ticks)
    supply = _number(fields, "supply", -1.0)
    seed = _whole(fields, "seed", 0, 2 ** 31 - 1)
    return Faults(missing, [parse_timed(u, PARAM)[:2] for u in items("unplug")], _number(fields, "lose", 0.0),
                  _number(fields, "corrupt", 0.0), [parse_timed(o, PARAM, 85.0) for o in items("overheat")],
                  None if supply < 0 else supply, seed or 0,
                  [(float(n), t) for n, t, _ in (parse_timed(p, PARAM, first="N") for p in items("push"))],
                  with_board(dict(parse_pair(m, PARAM) for m in items("model")), fields.get("board"), PARAM),
                  dict(parse_pair(e, PARAM, ALL_ERRORS) for e in items("errors")), horn)


def lockstep_robot(text: str, spec: Spec) -> LockstepPort:
    """An emulated OP2 in lockstep as ``text`` (:func:`parse_lockstep`) asks, and its port."""
    from op2motion.bus.emulator.server import Emulator

    setup = parse_lockstep(text)
    emulator = Emulator(spec, setup.engine, setup.start, setup.faults, timing=setup.timing,
                        return_delay=setup.return_delay, cold=setup.cold)
    return LockstepPort(emulator, text, setup.pace)


__all__ = ["KERNEL_LATENCY_TIMER_MS", "LockstepPort", "LockstepSetup", "is_lockstep", "lockstep_robot",
           "parse_lockstep"]
