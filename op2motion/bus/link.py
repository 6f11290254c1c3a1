"""The link to the robot in numbers: what a transaction costs (:class:`LinkBudget`), what the link was measured to
add (:func:`measure_link`), how many servos the 8 ms loop can read a tick (:func:`read_plan`), and the refusal
when it cannot hold its loop (:func:`too_slow`). A plan is tried on the link before a motion (:func:`tried_plan`):
what the registers and the pings do not show (a relay, a hub, a loaded PC) costs servos a tick, not missed reads.

A transaction's time ([``../shared/reference/bus_wire.md``]): the request's bytes and each reply's bytes at 10 bits a
byte (10 µs at 1 Mbps), each device's Return Delay Time (register 5, 2 µs a unit; the MX-28's factory value 250 is 0.5
ms, the OP2's servos are set to 0 by ROBOTIS's firmware installer), and the **tail**: what the USB adapter holds back
before the PC sees the last bytes. An FTDI FT232R sends a partial USB packet when its latency timer fires: 16 ms by
default on current Linux kernels, 1 ms once a program sets low latency (``ASYNC_LOW_LATENCY``) or writes 1 into
``/sys/bus/usb-serial/devices/ttyUSB0/latency_timer``. The tail is measured at connect: the board is pinged
:data:`PING_ROUNDS` rounds of :data:`PING_SAMPLES` times and the tail taken as the longest round trip of the best round
(but one) less its wire time, plus :data:`TAIL_MARGIN_S` (back-to-back pings meet the latency timer in the same phase
each time, so every trip shows its whole period); until then :data:`ASSUMED_TAIL_S` (the kernel's default timer) is
assumed, so that no reply is given up for lost on a slow link.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

from op2motion.bus.port import BAUD, sysfs_timer_path
from op2motion.bus.protocol import MIN_PACKET_BYTES
from op2motion.bus.tables import BOARD_SPAN, CM730_ID, MX28, SERVO_STATE_SPAN
from op2motion.errors import InputError, shown
from op2motion.jsonout import JsonObject

BYTE_S = 10.0 / BAUD               # one byte on the wire: start, 8 data, stop bits [s]
ASSUMED_TAIL_S = 0.017             # before the link is measured: the kernel's 16 ms latency timer, and 1 ms more
TAIL_MARGIN_S = 0.0005             # on top of the measured tail (a loaded PC's scheduling)
PING_SAMPLES = 6                   # pings in a round that measures the link at connect ...
PING_ROUNDS = 3                    # ... and rounds: the tail is the best round's longest trip but one (a trip
                                   # delayed by the PC, not by the link, must not make the link look slow)
BULK_READ_BYTES = 7                # a BULK_READ packet: FF FF FE LEN 92 00 ... CHK, and 3 bytes a device
BULK_READ_SPAN_BYTES = 3
PING_BYTES = 2 * MIN_PACKET_BYTES  # a ping and its reply
RETURN_DELAY_UNIT_S = 2e-6         # Return Delay Time register: 2 µs a unit
READ_BUDGET_S = 0.005             # a tick's reads end this long after it starts, whatever came (the controller and
                                   # the sync write, 1.5 ms on the wire, need the rest of the 8 ms)
PLAN_TRIALS = 5                    # bulk reads that try a plan before a motion
PLAN_BUDGET_S = 0.0035            # what a tick's read is planned to take: 1.5 ms of the above left for a late
                                   # start (the last tick's write still going out) and the PC's scheduling
MIN_SERVOS_PER_TICK = 2            # fewer, and each servo's position comes less often than every 80 ms: refused
PARAM = "port"


@dataclass
class LinkBudget:
    """A link's figures: one byte's time [s], the tail [s], each device's return delay [s] (unknown: 0)."""

    byte_s: float = BYTE_S
    tail_s: float = ASSUMED_TAIL_S
    delays_s: dict[int, float] = field(default_factory=dict)

    def reply_s(self, device: int, n_params: int) -> float:
        """One device's reply of ``n_params`` bytes: its return delay and its bytes [s]."""
        return self.delays_s.get(device, 0.0) + (n_params + MIN_PACKET_BYTES) * self.byte_s

    def first_and_last(self, request_bytes: int, order: Sequence[tuple[int, int]]) -> tuple[float, float]:
        """When a request's first and last replies are complete at the PC, counted from the request's writing
        [s]: the request's bytes, the replies one after the other in ``order`` ((id, parameter count)), the tail."""
        t = request_bytes * self.byte_s
        first = None
        for device, n in order:
            t += self.reply_s(device, n)
            first = t if first is None else first
        return (t if first is None else first) + self.tail_s, t + self.tail_s

    def gap_s(self, device: int | None) -> float:
        """The longest pause before ``device``'s reply while replies are coming [s]: the tail and its delay."""
        return self.tail_s + (self.delays_s.get(device, 0.0) if device is not None else 0.0)

    def bulk_read_s(self, spans: Iterable[tuple[int, int, int]]) -> float:
        """A BULK_READ of ``spans`` (id, address, length), from writing to its last reply, tail included [s]."""
        spans = list(spans)
        request = BULK_READ_BYTES + BULK_READ_SPAN_BYTES * len(spans)
        return self.first_and_last(request, [(d, n) for d, _, n in spans])[1]

    def wire_s(self, spans: Iterable[tuple[int, int, int]]) -> float:
        """A BULK_READ's time on the wire alone: bytes and return delays, no tail [s]."""
        return self.bulk_read_s(spans) - self.tail_s


@dataclass(frozen=True)
class LinkCheck:
    """What the link was measured to be at connect: the adapter's latency timer [ms] (None where the port has none
    to read), what setting low latency gave, the ping round trips [s] and the tail taken from them [s] (the link's
    own hold, without the PC's occasional delays: see :func:`measure_link`)."""

    latency_timer_ms: int | None
    low_latency: str
    round_trips_s: tuple[float, ...]
    tail_s: float

    @property
    def median_round_trip_s(self) -> float | None:
        """The median ping round trip [s] (None: no ping answered)."""
        trips = sorted(self.round_trips_s)
        return trips[len(trips) // 2] if trips else None

    def as_dict(self) -> JsonObject:
        """JSON-ready (milliseconds)."""
        median = self.median_round_trip_s
        return {"latency_timer_ms": self.latency_timer_ms, "low_latency": self.low_latency,
                "ping_round_trip_ms": {"median": None if median is None else median * 1000,
                                       "max": max(self.round_trips_s) * 1000 if self.round_trips_s else None},
                "tail_ms": self.tail_s * 1000}

    def describe(self) -> str:
        """One line for people."""
        timer = "unknown (not a USB serial adapter)" if self.latency_timer_ms is None else \
            f"{self.latency_timer_ms} ms"
        trips = sorted(self.round_trips_s)
        rtt = (f"ping round trip {trips[len(trips) // 2] * 1000:.2f} ms (max {trips[-1] * 1000:.2f} ms)"
               if trips else "no ping answered")
        how = f" ({self.low_latency})" if self.latency_timer_ms is not None and self.low_latency else ""
        return f"link: FTDI latency timer {timer}{how}; {rtt}"


def measure_link(bus: Any, device: int, latency_timer_ms: int | None, low_latency: str,
                 samples: int = PING_SAMPLES, rounds: int = PING_ROUNDS) -> LinkCheck:
    """Ping ``device`` ``rounds`` x ``samples`` times on ``bus`` (a :class:`~.client.Bus`) and set its tail from
    the best round's longest round trip but one (see the module docstring); the :class:`LinkCheck` (all the
    trips)."""
    trips: list[float] = []
    worst: list[float] = []
    for _ in range(rounds):
        these = []
        for _ in range(samples):
            t0 = bus.clock.now()
            if bus.ping(device, retries=0) is not None:
                these.append(bus.clock.now() - t0)
        trips += these
        if these:
            worst.append(sorted(these)[-2] if len(these) > 2 else max(these))
    if worst:
        wire = PING_BYTES * bus.link.byte_s + bus.link.delays_s.get(device, 0.0)
        bus.link.tail_s = max(min(worst) - wire, 0.0) + TAIL_MARGIN_S
    return LinkCheck(latency_timer_ms, low_latency, tuple(trips), bus.link.tail_s)


def return_delays(budget: LinkBudget, registers: dict[int, int]) -> None:
    """Each device's Return Delay Time register (``{id: value}``, 2 µs units) into ``budget``."""
    budget.delays_s.update({d: v * RETURN_DELAY_UNIT_S for d, v in registers.items()})


@dataclass(frozen=True)
class ReadPlan:
    """What the 8 ms loop reads a tick, from the link's budget: the board's span every tick, ``servos_per_tick``
    servos' positions (all of them when the link allows; else a window moving round the servos, each read every
    ``ceil(count / servos_per_tick)`` ticks, as the stock framework reads only the board), one of them its whole
    state in turn; ``tick_s``: such a read from writing to its last reply, tail included [s]; ``wire_s``: its bytes
    and return delays alone [s]."""

    servos_per_tick: int
    count: int
    tick_s: float
    wire_s: float

    def spans(self, k: int, ids: Sequence[int]) -> tuple[list[tuple[int, int, int]], int | None]:
        """Tick ``k``'s bulk read (id, address, length) and the servo whose whole state it reads."""
        n, m = len(ids), self.servos_per_tick
        if m >= n:
            servos, rotating = list(ids), ids[k % n] if n else None
        elif m == 0:
            servos, rotating = [], None
        else:
            start = (k * m) % n
            servos = [ids[(start + i) % n] for i in range(m)]
            rotating = servos[(k // math.ceil(n / m)) % m]
        return tick_spans(servos, rotating), rotating

    def as_dict(self) -> JsonObject:
        """JSON-ready (milliseconds)."""
        return {"servos_per_tick": self.servos_per_tick, "servos": self.count,
                "bulk_read_ms": round(self.tick_s * 1000, 3), "bulk_read_wire_ms": round(self.wire_s * 1000, 3)}


def tick_spans(servos: Sequence[int], rotating: int | None) -> list[tuple[int, int, int]]:
    """A tick's bulk read: the board's span (:data:`~.tables.BOARD_SPAN`), then each servo's present position, or
    its whole state (:data:`~.tables.SERVO_STATE_SPAN`) for ``rotating``."""
    position = MX28["present_position"].address
    return [(CM730_ID, *BOARD_SPAN)] + [(d, *SERVO_STATE_SPAN) if d == rotating else (d, position, 2)
                                        for d in servos]


def read_plan(budget: LinkBudget, ids: Sequence[int], read_budget_s: float = PLAN_BUDGET_S) -> ReadPlan:
    """The most servos a tick can read within ``read_budget_s`` [s] (see :class:`ReadPlan`), judged with the slowest
    servos' return delays."""
    for m in range(len(ids), 0, -1):
        plan = plan_of(budget, ids, m)
        if plan.tick_s <= read_budget_s:
            return plan
    return plan_of(budget, ids, 0)


def plan_of(budget: LinkBudget, ids: Sequence[int], m: int) -> ReadPlan:
    """A tick reading ``m`` servos, its times judged with the slowest servos' return delays."""
    slowest = sorted(ids, key=lambda d: -budget.delays_s.get(d, 0.0))
    spans = tick_spans(slowest[:m], slowest[0] if m else None)
    return ReadPlan(m, len(ids), budget.bulk_read_s(spans), budget.wire_s(spans))


def tried_plan(bus: Any, ids: Sequence[int], plan: ReadPlan, read_budget_s: float = PLAN_BUDGET_S) -> ReadPlan:
    """``plan`` as the link really answers: :data:`PLAN_TRIALS` bulk reads of its ticks on ``bus`` (a
    :class:`~.client.Bus`); while the slowest but one takes longer than ``read_budget_s`` [s] (delays the registers
    do not show: a relay, a hub, a loaded PC), one servo fewer a tick; a plan of 0 when not even the board fits."""
    m = plan.servos_per_tick
    while m > 0:
        trial = plan_of(bus.link, ids, m)
        took = []
        for k in range(PLAN_TRIALS):
            spans, _ = trial.spans(k, ids)
            t0 = bus.clock.now()
            got = bus.bulk_read(spans, 0.0, t0 + READ_BUDGET_S)
            took.append(bus.clock.now() - t0 if len(got) == len(spans) else READ_BUDGET_S)
        if sorted(took)[-2] <= read_budget_s:
            return trial
        m -= 1
    return plan_of(bus.link, ids, 0)


def too_slow(check: LinkCheck, board_s: float, port_path: str, servos: int = 0, return_delay: int = 0,
             read_budget_s: float = PLAN_BUDGET_S) -> InputError:
    """The refusal of a motion on a link that cannot hold the 8 ms loop (a tick reads ``servos`` servos beside the
    board; ``return_delay``: the servos' largest register value): names the cause and its fix, the servos' return
    delay where it is not 0, else the latency timer."""
    trips = sorted(check.round_trips_s)
    worst = f"{trips[-1] * 1000:.1f} ms" if trips else "no reply"
    why = (f"the link is too slow for the 8 ms loop: a tick's read holds the sub-controller and {servos} servos "
           f"(at least {MIN_SERVOS_PER_TICK} needed) in {read_budget_s * 1000:.1f} ms")
    if return_delay > 0:
        return InputError(f"{why}; the servos' return delay is up to {return_delay} ({return_delay * 2} µs a reply): "
                          f"set it to 0 with 'op2motion robot setup --port {shown(port_path)} --return-delay 0'; "
                          f"nothing moved", PARAM)
    timer = "at an unknown value" if check.latency_timer_ms is None else f"at {check.latency_timer_ms} ms"
    return InputError(
        f"{why} (a ping's round trip took up to {worst}; the sub-controller's read alone {board_s * 1000:.1f} ms); the "
        f"FTDI USB adapter's latency timer is {timer} (current kernels leave it at 16 ms): set it to 1 ms with "
        f"'echo 1 | sudo tee {shown(sysfs_timer_path(port_path))}' (to keep it, the udev rule in docs/robot.md); "
        f"nothing moved", PARAM)
