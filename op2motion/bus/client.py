"""Protocol 1.0 transactions on a :class:`~.port.Port`: ping, read, write, sync write and bulk read, each bounded in
time and retried a bounded number of times.

Before each request the input is flushed (a late reply of an earlier request must not be taken for this one's);
a reply counts only when it comes from the device asked and carries the length asked for; an echo of our own
packet is skipped. The wait for the first byte is the request's time on the wire plus a latency allowance (the USB
adapter, the device's return delay); once replies come, a pause of :data:`GAP_S` ends the wait (devices answer back
to back, so the rest were lost), and the whole wait never exceeds the replies' time on the wire (1.5 x, 10 bits a
byte at 1 Mbps) on top of that. A device that does not answer, answers
garbage or reports a checksum or instruction error (our packet arrived damaged) is asked again, at most
``retries`` more times; then the transaction returns None and the caller decides.

:meth:`Bus.bulk_read` is one try by design: the 8 ms loop asks again for only the devices that did not answer
(:mod:`.loop`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Sequence

from op2motion.bus import protocol as p
from op2motion.bus.port import BAUD, Port

BYTE_S = 10.0 / BAUD               # one byte on the wire: start, 8 data, stop bits
WIRE_MARGIN = 1.5                  # replies may take this much longer than their bytes
COMMAND_LATENCY_S = 0.012          # one-off commands: allowance for a device (and a USB adapter) to answer
RETRIES = 3                        # a one-off command is tried 1 + RETRIES times
GAP_S = 0.0015                     # replies that stop this long are over (a USB adapter's low-latency timer: 1 ms)


@dataclass
class BusStats:
    """What the bus saw: requests sent, replies that never came, packets thrown away, retries."""

    requests: int = 0
    timeouts: int = 0
    bad_checksums: int = 0
    stray: int = 0
    retries: int = 0
    device_errors: dict[int, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {"requests": self.requests, "timeouts": self.timeouts, "bad_checksums": self.bad_checksums,
                "stray_packets": self.stray, "retries": self.retries}


class Bus:
    """Transactions on one port (see the module docstring)."""

    def __init__(self, port: Port, retries: int = RETRIES, latency_s: float = COMMAND_LATENCY_S):
        self.port, self.retries, self.latency_s = port, retries, latency_s
        self.parser = p.StreamParser()
        self.stats = BusStats()

    def _send(self, packet: bytes) -> None:
        self.port.flush_input()
        self.parser.clear()
        self.stats.requests += 1
        self.port.write(packet)

    def _collect(self, sent: bytes, expect: Mapping[int, int], latency_s: float, cap: float | None = None
                 ) -> dict[int, p.Packet]:
        """Replies to ``sent`` from the devices in ``expect`` ({id: parameter count}), until all came, or nothing
        came within ``latency_s`` (plus the request's wire time), or the replies stopped for :data:`GAP_S` (devices
        answer back to back: a gap means the rest were lost), or the whole wait (all bytes' wire time + the
        latency) is over, or the monotonic time ``cap``."""
        now = time.monotonic()
        first = now + len(sent) * BYTE_S * WIRE_MARGIN + latency_s
        end = first + sum(n + p.MIN_PACKET_BYTES for n in expect.values()) * BYTE_S * WIRE_MARGIN
        if cap is not None:
            first, end = min(first, cap), min(end, cap)
        got: dict[int, p.Packet] = {}
        echo_skipped = False
        bad_before = self.parser.bad_checksums
        last: float | None = None
        while len(got) < len(expect):
            deadline = first if last is None else min(end, last + GAP_S)
            data = self.port.read(deadline)
            if not data:
                if time.monotonic() >= deadline:
                    break
                continue
            last = time.monotonic()
            for packet in self.parser.feed(data):
                if not echo_skipped and packet.encode() == sent:
                    echo_skipped = True
                    continue
                if packet.id in expect and packet.id not in got and len(packet.params) == expect[packet.id]:
                    got[packet.id] = packet
                else:
                    self.stats.stray += 1
        self.stats.bad_checksums += self.parser.bad_checksums - bad_before
        if len(got) < len(expect):
            self.stats.timeouts += 1
        return got

    def _transact(self, device: int, packet: bytes, n_params: int, retries: int | None = None) -> p.Packet | None:
        """One request to one device, retried; its status packet, or None."""
        tries = 1 + (self.retries if retries is None else retries)
        for attempt in range(tries):
            if attempt:
                self.stats.retries += 1
            self._send(packet)
            reply = self._collect(packet, {device: n_params}, self.latency_s).get(device)
            if reply is None:
                continue
            if reply.code & (p.CHECKSUM | p.INSTRUCTION):     # our packet arrived damaged: say it again
                self.stats.device_errors[device] = self.stats.device_errors.get(device, 0) + 1
                continue
            return reply
        return None

    def ping(self, device: int, retries: int | None = None) -> p.Packet | None:
        """PING ``device``: its status packet (error byte in ``code``), or None if it does not answer."""
        return self._transact(device, p.ping(device), 0, retries)

    def read(self, device: int, address: int, length: int, retries: int | None = None) -> p.Packet | None:
        """READ ``length`` bytes from ``address``: the status packet (``params`` the bytes), or None."""
        return self._transact(device, p.read(device, address, length), length, retries)

    def write(self, device: int, address: int, data: bytes | Sequence[int], reply: bool = True,
              retries: int | None = None) -> p.Packet | None:
        """WRITE ``data`` from ``address``; with ``reply`` (status return level 2) wait for the status packet and
        return it (None: no answer after the retries); without, send once and return None."""
        packet = p.write(device, address, data)
        if not reply or device == p.BROADCAST_ID:
            self._send(packet)
            return None
        return self._transact(device, packet, 0, retries)

    def sync_write(self, address: int, length: int, data: Mapping[int, bytes | Sequence[int]]) -> None:
        """SYNC_WRITE (no reply)."""
        if data:
            self._send(p.sync_write(address, length, data))

    def bulk_read(self, spans: Iterable[tuple[int, int, int]], latency_s: float, until: float | None = None
                  ) -> dict[int, p.Packet]:
        """One BULK_READ of ``spans`` (id, address, length); the status packets that came within the wait (at the
        latest at the monotonic time ``until``), by id."""
        spans = list(spans)
        if not spans:
            return {}
        packet = p.bulk_read(spans)
        self._send(packet)
        return self._collect(packet, {device: length for device, _, length in spans}, latency_s, until)
