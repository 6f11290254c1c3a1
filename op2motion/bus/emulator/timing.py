"""The wire between the robot's PC and its devices, in time: what a real CM-730 (CM-740) behind its FTDI FT232R
costs, so that the emulated OP2 answers when a real one would, not as fast as a pseudo-terminal can.

:class:`WireTiming` holds the figures (``../shared/reference/bus_wire.md``; ROBOTIS's MX-28 e-manual; Linux's
``ftdi_sio``; FTDI's AN232B-04 on the latency timer):

* **bytes at the baud rate**: 10 bits a byte (start, 8 data, stop), 10 µs at 1 Mbps; the host's requests go out one
  after the other (the adapter's transmit line is serial); the bus is half duplex: a device answers after the
  request's last byte;
* **each device's Return Delay Time** (register 5, 2 µs a unit) before its reply, and in a bulk read the replies one
  after the other in the request's order, each device waiting its own delay after the previous reply;
* **the USB adapter's receive path** (:mod:`.ftdi`): the FT232R sends what it received in USB packets of at most
  :data:`USB_PAYLOAD_BYTES` bytes (64 with its 2 status bytes); a full packet goes at once, a partial one waits for
  the latency timer, which fires every ``latency_timer_s`` and restarts at every packet sent (an empty one too).

Not modelled: the host's USB OUT scheduling (the request is on the wire the moment it is written), collisions
(a request written while replies are on the bus), the CM-730's own relaying delay.

:class:`TimedLink` applies them: the host's bytes in (:meth:`TimedLink.send`), the requests handed to the devices
when their last byte is on the wire (``answer``), the replies' bytes onto the wire after their return delays, and
the USB packets out when the adapter would send them (:meth:`TimedLink.run_until`). Time is whatever scale the
caller keeps [s]: the emulator's simulated time. With ``WireTiming.instant`` nothing waits: a request is answered
when it is written and its replies are there at once (a pseudo-terminal's speed).
"""

from __future__ import annotations

import collections
from dataclasses import dataclass
from typing import Callable

from op2motion.bus.emulator.ftdi import USB_PAYLOAD_BYTES, Ftdi
from op2motion.errors import InputError

RETURN_DELAY_UNIT_S = 2e-6         # Return Delay Time register (address 5): 2 µs a unit
LATENCY_TIMERS_MS = (1, 16)        # what the timer is after a client sets low latency / on a current kernel
DEFAULT_LATENCY_TIMER_MS = 1       # the emulator's: what op2motion's client sets at open (ASYNC_LOW_LATENCY)
KERNEL_LATENCY_TIMER_MS = 16       # Linux ftdi_sio's default since the low-latency default was removed
MAX_LATENCY_TIMER_MS = 255         # FT232R: 1..255 ms

Answer = Callable[[float, bytes], list[bytes]]
__all__ = ["DEFAULT_LATENCY_TIMER_MS", "INSTANT", "KERNEL_LATENCY_TIMER_MS", "USB_PAYLOAD_BYTES", "Ftdi", "TimedLink",
           "WireTiming", "packet_ends", "return_delay_s"]


@dataclass(frozen=True)
class WireTiming:
    """The wire's figures: ``baud`` [bit/s], the FTDI ``latency_timer_s`` [s], and ``instant`` (no wire at all)."""

    baud: int = 1_000_000
    latency_timer_s: float = DEFAULT_LATENCY_TIMER_MS / 1000.0
    instant: bool = False

    def __post_init__(self) -> None:
        if not self.instant and not 1e-3 <= self.latency_timer_s <= MAX_LATENCY_TIMER_MS * 1e-3 + 1e-12:
            raise InputError(f"expected a latency timer of 1 to {MAX_LATENCY_TIMER_MS} ms, got "
                             f"{self.latency_timer_s * 1000:g} ms", "latency_timer_ms")
        if self.baud <= 0:
            raise InputError(f"expected a positive baud rate, got {self.baud}", "baud")

    @property
    def byte_s(self) -> float:
        """One byte on the wire [s]: start, 8 data and stop bits."""
        return 10.0 / self.baud

    def describe(self) -> str:
        """For people."""
        if self.instant:
            return "instant wire"
        return f"{self.baud / 1e6:g} Mbps wire, FTDI latency timer {self.latency_timer_s * 1000:g} ms"


#: A pseudo-terminal's speed: no byte times, no delays, no USB packets.
INSTANT = WireTiming(instant=True)


def packet_ends(stream: bytes | bytearray) -> list[int]:
    """The offsets just past each complete Protocol 1.0 packet in ``stream`` (bytes before a header belong to the
    packet after them), by the header and LEN only: the devices judge the checksum."""
    ends: list[int] = []
    i, n = 0, len(stream)
    while True:
        start = stream.find(b"\xff\xff", i)
        while 0 <= start < n - 2 and stream[start + 2] == 0xFF:
            start += 1
        if start < 0 or start + 4 > n:
            return ends
        end = start + 4 + stream[start + 3]
        if end > n:
            return ends
        ends.append(end)
        i = end


class TimedLink:
    """The PC's port, the half-duplex bus and the devices' replies in time (see the module docstring).

    ``answer(t, request)`` gives a request's replies (one chunk per reply, a bulk read's together) when the request's
    last byte is on the wire at ``t``; ``delay_s(id)`` a device's return delay [s]; ``start_s`` the time now [s]."""

    def __init__(self, timing: WireTiming, answer: Answer, delay_s: Callable[[int], float], start_s: float = 0.0):
        self.timing, self.answer, self.delay_s = timing, answer, delay_s
        self.byte_s = timing.byte_s
        self.host = bytearray()                      # the host's bytes not yet handed to the devices
        self.host_times: collections.deque[tuple[int, float]] = collections.deque()  # (offset in host, its start)
        self.requests: collections.deque[tuple[float, bytes]] = collections.deque()  # (last byte's end, packet)
        self.tx_free_s = start_s                     # the host's line is free from then
        self.bus_free_s = start_s                    # the devices' replies: the bus is free from then
        self.ftdi = Ftdi(timing.latency_timer_s, self.byte_s, start_s)
        self.ready: list[bytes] = []                 # instant wire: replies waiting to be read

    # --- the host's side -------------------------------------------------------------------------------------------
    def send(self, t: float, data: bytes) -> None:
        """The host wrote ``data`` at ``t`` [s]."""
        if self.timing.instant:
            self.host += data
            for end in packet_ends(self.host):
                self.ready += self.answer(t, bytes(self.host[:end]))
                del self.host[:end]
            return
        start = max(t, self.tx_free_s)
        self.host_times.append((len(self.host), start))
        self.host += data
        self.tx_free_s = start + len(data) * self.byte_s
        self._frame()

    def _frame(self) -> None:
        """Complete packets in the host's bytes become requests, timed by their last byte."""
        cut = 0
        for end in packet_ends(self.host):
            self.requests.append((self._end_of(end - 1), bytes(self.host[cut:end])))
            cut = end
        if cut:
            del self.host[:cut]
            shifted = [(offset - cut, t) for offset, t in self.host_times]
            keep = [s for s in shifted if s[0] > 0]
            first = [s for s in shifted if s[0] <= 0][-1:]
            if first:                                # the segment holding the new first byte
                offset, t = first[0]
                keep.insert(0, (0, t - offset * self.byte_s))
            self.host_times = collections.deque(keep)

    def _end_of(self, index: int) -> float:
        """When the host's byte at ``index`` is complete on the wire [s]."""
        offset, start = next((o, t) for o, t in reversed(self.host_times) if o <= index)
        return start + (index - offset + 1) * self.byte_s

    # --- time passing ------------------------------------------------------------------------------------------------
    def next_event(self) -> float | None:
        """When something next happens without more bytes from the host: a request reaching the devices, or a USB
        packet with bytes in it [s]; None if nothing is under way."""
        if self.timing.instant:
            return None
        nxt = self.requests[0][0] if self.requests else None
        sent = self.ftdi.next_packet()
        if sent is not None and (nxt is None or sent < nxt):
            nxt = sent
        return nxt

    def run_until(self, t: float) -> list[bytes]:
        """Everything that happens up to ``t`` [s]; the bytes the host receives by then, in USB packets."""
        if self.timing.instant:
            out, self.ready = self.ready, []
            return out
        out = []
        requests = self.requests
        while requests and requests[0][0] <= t:
            due, request = requests[0]
            out += self.ftdi.run(due)
            requests.popleft()
            self._replies(due, self.answer(due, request))
        out += self.ftdi.run(t)
        return out

    def _replies(self, t: float, chunks: list[bytes]) -> None:
        """Put the replies to a request that reached the devices at ``t`` onto the wire, each after its device's
        return delay, one after the other."""
        cursor = max(t, self.bus_free_s)
        for chunk in chunks:
            for reply in _split(chunk):
                start = cursor + self.delay_s(reply[2] if len(reply) > 2 else 0)
                self.ftdi.receive(start + self.byte_s, reply)
                cursor = start + len(reply) * self.byte_s
        self.bus_free_s = cursor


def _split(chunk: bytes) -> list[bytes]:
    """A chunk of back-to-back status packets as its packets (what cannot be split stays one)."""
    pieces: list[bytes] = []
    i = 0
    for end in packet_ends(chunk):
        pieces.append(chunk[i:end])
        i = end
    if i < len(chunk):
        pieces.append(chunk[i:])
    return [piece for piece in pieces if piece]


def return_delay_s(register: int) -> float:
    """A Return Delay Time register's value as seconds."""
    return register * RETURN_DELAY_UNIT_S
