"""The FT232R's receive path: the bytes of the devices' replies in as they finish on the wire, USB packets out to
the PC (:mod:`.timing` has the figures and their sources). A packet holds at most :data:`USB_PAYLOAD_BYTES` bytes
(64 with the chip's 2 status bytes); a full one goes at once, a partial one waits for the latency timer, which
fires every ``timer_s`` and restarts at every packet sent (an empty one too).
"""

from __future__ import annotations

import collections
import math

USB_PAYLOAD_BYTES = 62             # FT232R: 64-byte USB packets, 2 of them modem status


class Ftdi:
    """The FT232R's receive path (see the module docstring): bytes in as they finish on the wire, USB packets out.

    :meth:`next_packet` (when the next packet with bytes in it goes, were nothing more to arrive) is worked out from
    the chip's state without changing it, by the arithmetic :meth:`step` does, and kept until the state changes: the
    emulator asks it several times between two changes."""

    def __init__(self, latency_timer_s: float, byte_s: float, start_s: float):
        self.timer_s, self.byte_s = latency_timer_s, byte_s
        self.anchor = start_s                       # the last packet sent: the timer fires timer_s after it
        self.buffer = bytearray()
        self.incoming: collections.deque[tuple[float, bytes]] = collections.deque()   # (first byte's end, bytes)
        self._next: float | None = None              # next_packet's answer, while _next_known
        self._next_known = False

    def receive(self, first_end_s: float, data: bytes) -> None:
        """``data`` arrives back to back, its first byte complete at ``first_end_s`` [s]."""
        if data:
            self.incoming.append((first_end_s, data))
            self._next_known = False

    def idle(self) -> bool:
        """Nothing buffered and nothing on its way."""
        return not self.buffer and not self.incoming

    def step(self, limit_s: float) -> tuple[float, bytes] | None:
        """The next thing the chip does at or before ``limit_s``: a USB packet sent (its time and payload; an empty
        payload for a timer firing with nothing buffered), bytes taken in (returns ``(t, b"")`` too), or None when
        nothing happens by then."""
        fire = self.anchor + self.timer_s
        if not self.buffer and not self.incoming:    # idle: skip whole idle periods at once
            if fire > limit_s or math.isinf(limit_s):
                return None
            periods = max(1, math.floor((limit_s - self.anchor) / self.timer_s + 1e-9))
            self.anchor += periods * self.timer_s
            return self.anchor, b""
        self._next_known = False
        by = fire if fire < limit_s else limit_s
        if self.incoming and self.incoming[0][0] <= by:
            return self._take_in(by)
        if fire <= limit_s:
            return self._send(fire)
        return None

    def _take_in(self, by: float) -> tuple[float, bytes]:
        """Bytes taken in: what of the incoming replies is complete by ``by`` [s], reply after reply while each comes
        whole (one step each, as it were, taken together: nothing else happens between them), up to a full packet
        (sent at once)."""
        incoming, buffer, byte_s = self.incoming, self.buffer, self.byte_s
        while True:
            first, data = incoming[0]
            done = int((by - first) / byte_s + 1e-9) + 1             # the bytes complete by then (int: floor, >= 0)
            take = min(len(data), done, USB_PAYLOAD_BYTES - len(buffer))
            buffer += data[:take]
            whole = take == len(data)
            if whole:
                incoming.popleft()
            else:
                incoming[0] = (first + take * byte_s, data[take:])
            at = first + (take - 1) * byte_s
            if len(buffer) == USB_PAYLOAD_BYTES:                      # a full packet goes at once
                return self._send(at)
            if not whole or not incoming or incoming[0][0] > by:
                return at, b""

    def run(self, limit_s: float) -> list[bytes]:
        """Everything the chip does up to ``limit_s`` [s]: the payloads of the USB packets with bytes in them it
        sends by then."""
        out: list[bytes] = []
        if not self.buffer and not self.incoming and self.anchor + self.timer_s > limit_s:
            return out                                # idle, and the timer does not fire by then: step's first case
        while (event := self.step(limit_s)) is not None:
            if event[1]:
                out.append(event[1])
        return out

    def next_packet(self) -> float | None:
        """When the chip sends its next packet with bytes in it [s], from what it holds and receives so far (None:
        nothing held or on its way): :meth:`step` without a limit, on the state's numbers, nothing changed."""
        if not self._next_known:
            self._next, self._next_known = self._first_packet(), True
        return self._next

    def _first_packet(self) -> float | None:
        """:meth:`step`'s arithmetic with no limit, on copies of the state's numbers."""
        anchor, held, timer_s, byte_s = self.anchor, len(self.buffer), self.timer_s, self.byte_s
        for first, data in self.incoming:
            size = len(data)
            while True:                                                # this reply, in one take or several
                fire = anchor + timer_s
                if first <= fire:
                    take = min(size, int((fire - first) / byte_s + 1e-9) + 1, USB_PAYLOAD_BYTES - held)
                    held += take
                    if held == USB_PAYLOAD_BYTES:                      # a full packet goes at once
                        return first + (take - 1) * byte_s
                    if take == size:
                        break
                    first, size = first + take * byte_s, size - take
                elif held:
                    return fire
                else:
                    anchor = fire                                      # an empty packet: the timer restarts
        return anchor + timer_s if held else None

    def _send(self, t: float) -> tuple[float, bytes]:
        payload = bytes(self.buffer)
        self.buffer.clear()
        self.anchor = t
        return t, payload
