"""Protocol 1.0 transactions on a port: ping, read, write, sync write and bulk read, each bounded in time and
retried a bounded number of times, on the port's clock (:mod:`.clock`: the wall, or an emulator's lockstep time).

**How long a reply may take** (:class:`~.link.LinkBudget`): the request's and the replies' bytes at the baud rate,
each device's return delay, and the link's tail: what the USB adapter holds back (an FTDI's latency timer) and the
system adds, as measured at connect (:func:`~.link.measure_link`; until then the kernel's default timer, 16 ms, is
assumed). The wait for the first reply is its time on the wire plus the tail; once replies come, a pause of the tail
plus the next device's delay ends the wait (devices answer back to back: a longer pause means the rest were lost);
the whole wait never exceeds all the replies' time plus the tail. A caller with a budget (the 8 ms loop's read:
``cap``) waits for every reply until the cap instead: the budget is the loop's anyway, and what the PC adds to a
reply's way varies more than the wire does. Every wait counts from when the
request's first byte can go out: after the bytes written before it (the loop's sync write takes 1.5 ms).

**Replies that come late** (after their wait ended) are never taken for a later request's: the devices a request still
owed are kept, in order, until a reply to a later request comes (the bus and the USB adapter keep the order: nothing
late can follow it). Before that, a reply matching one of them (by ID and length) is that late reply, dropped and
counted (``stray_packets``), unless it is from the new request's first device and one more tail has passed since the old
wait's end (a late reply would have come by then) and it could be the new reply (it is not complete before the request's
and that reply's bytes at the baud rate and its return delay). A reply nothing owes is never late (an emulator without a
wire model answers faster than a wire could); anything the port held before a request went out is dropped and counted
too. A one-off command asks again only after that window (so a retry's reply is never mistaken for the late one). A
reply counts only when it comes from a device asked and carries the length asked for; an echo of our own packet is
skipped. A device that does not answer or answers garbage is asked again, at most ``retries`` more times; then the
transaction returns None and the caller decides. A status packet is an answer, whatever its error bits: one with the
checksum or instruction bit (our packet may have arrived damaged) is asked again :data:`DAMAGED_RETRIES` time(s)
within those tries, and if the bits stay, that reply is returned, for the caller to name its bits (a device that
reports them on every reply is not one that is silent).

:meth:`Bus.bulk_read` is one try by design: the 8 ms loop asks again for only the devices that did not answer
(:mod:`.loop`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Mapping, Sequence

from op2motion.bus import protocol as p
from op2motion.bus.clock import Clock
from op2motion.bus.link import ASSUMED_TAIL_S, LinkBudget
from op2motion.bus.port import PortLike

RETRIES = 3                        # a one-off command is tried 1 + RETRIES times
DAMAGED_RETRIES = 1                # ... asked again this often when the reply says our packet arrived damaged
DAMAGED = p.CHECKSUM | p.INSTRUCTION   # the error bits that say so
MAX_OWED = 64                      # late replies remembered at most
COMMAND_MARGIN_S = 0.003           # one-off commands: beyond the wire's own figures (a loaded PC's scheduling)


@dataclass
class BusStats:
    """What the bus saw: requests sent, replies that never came, packets thrown away (late replies, noise),
    retries."""

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
    """Transactions on one port (see the module docstring). ``margin_s`` is what one-off commands allow beyond the
    wire's figures."""

    def __init__(self, port: PortLike, retries: int = RETRIES, margin_s: float = COMMAND_MARGIN_S):
        self.port, self.retries, self.margin_s = port, retries, margin_s
        self.clock: Clock = port.clock
        self.link = LinkBudget(tail_s=ASSUMED_TAIL_S)
        self.parser = p.StreamParser()
        self.stats = BusStats()
        self.owed: list[tuple[int, int]] = []           # (id, parameter count) a request still owes, in order
        self.owed_until = 0.0                           # ... which can no longer come after this time
        self.sent_at = self.tx_free = 0.0               # the last request's first byte goes out / the line is free

    def _send(self, packet: bytes) -> None:
        for held in self.parser.feed(self.port.flush_input()):
            self._late(held, None)
            self.stats.stray += 1
        self.parser.clear()
        self.stats.requests += 1
        self.sent_at = max(self.clock.now(), self.tx_free)
        self.tx_free = self.sent_at + len(packet) * self.link.byte_s
        self.port.write(packet)

    def _late(self, packet: p.Packet, first: int | None, earliest: float = 0.0) -> bool:
        """Whether ``packet``, come before any reply to the request now waited for (whose first device is ``first``;
        no reply to it can be complete before the time ``earliest``), is a reply an earlier request still owed (then
        it is dropped from what is owed): one come before ``earliest`` is; a device the new request does not ask
        first cannot be answering it yet; its first device can, once the late window is over. A packet nothing
        owes is never late (an emulator without a wire model answers faster than a wire could)."""
        key = (packet.id, len(packet.params))
        if key not in self.owed:
            return False
        if packet.id == first and self.clock.now() >= earliest and self.clock.now() > self.owed_until:
            self.owed = []
            return False
        del self.owed[:self.owed.index(key) + 1]
        return True

    def _collect(self, sent: bytes, expect: Mapping[int, int], margin_s: float, cap: float | None = None
                 ) -> dict[int, p.Packet]:
        """Replies to ``sent`` from the devices in ``expect`` ({id: parameter count}, in the order they answer),
        within the waits of the module docstring (``margin_s`` on top of each; never past the time ``cap``)."""
        now = self.sent_at                              # after what we wrote before it (a sync write: 1.5 ms)
        order = list(expect.items())
        earliest = now + self.link.first_and_last(len(sent), order[:1])[0] - self.link.tail_s - self.link.byte_s
        first, end = self.link.first_and_last(len(sent), order)
        first, end = now + first + margin_s, now + end + margin_s
        if cap is not None:                             # a budget: use all of it (what the PC adds varies)
            first = end = cap
        got: dict[int, p.Packet] = {}
        echo_skipped = False
        bad_before = self.parser.bad_checksums
        last: float | None = None
        while len(got) < len(expect):
            nxt = next((d for d, _ in order if d not in got), None)
            deadline = first if last is None else end if cap is not None else \
                min(end, last + self.link.gap_s(nxt) + margin_s)
            data = self.port.read(deadline)
            if not data:
                if self.clock.now() >= deadline:
                    break
                continue
            last = self.clock.now()
            for packet in self.parser.feed(data):
                if not echo_skipped and packet.encode() == sent:
                    echo_skipped = True
                elif not got and self._late(packet, order[0][0], earliest):
                    self.stats.stray += 1
                elif packet.id in expect and packet.id not in got and len(packet.params) == expect[packet.id]:
                    got[packet.id] = packet
                    self.owed = []                      # late replies would have come before this one
                else:
                    self.stats.stray += 1
        self.stats.bad_checksums += self.parser.bad_checksums - bad_before
        if len(got) < len(expect):
            self.stats.timeouts += 1
            self.owed = (self.owed + [(d, n) for d, n in order if d not in got])[-MAX_OWED:]
            self.owed_until = end + self.link.tail_s
        return got

    def _transact(self, device: int, packet: bytes, n_params: int, retries: int | None = None) -> p.Packet | None:
        """One request to one device, retried (see the module docstring); its status packet (error bits and all),
        or None if it never answered."""
        tries = 1 + (self.retries if retries is None else retries)
        damaged: p.Packet | None = None                 # the last reply that said our packet arrived damaged
        said_again = 0
        for attempt in range(tries):
            if attempt:
                self.stats.retries += 1
                self.settle()
            self._send(packet)
            reply = self._collect(packet, {device: n_params}, self.margin_s).get(device)
            if reply is None:
                continue
            if reply.code & DAMAGED:
                self.stats.device_errors[device] = self.stats.device_errors.get(device, 0) + 1
                damaged = reply
                if said_again < DAMAGED_RETRIES:        # perhaps it was: say it again, once
                    said_again += 1
                    continue
            return reply
        return damaged

    def settle(self) -> None:
        """Wait until no late reply is owed any more (see the module docstring)."""
        if self.owed:
            self.clock.sleep_until(self.owed_until)
            self.owed = []

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

    def bulk_read(self, spans: Iterable[tuple[int, int, int]], margin_s: float, until: float | None = None
                  ) -> dict[int, p.Packet]:
        """One BULK_READ of ``spans`` (id, address, length); the status packets that came within the wait (at the
        latest at the time ``until`` on the bus's clock), by id."""
        spans = list(spans)
        if not spans:
            return {}
        packet = p.bulk_read(spans)
        self._send(packet)
        return self._collect(packet, {device: length for device, _, length in spans}, margin_s, until)
