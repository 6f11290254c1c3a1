"""The wire as it is, without physics: the emulator's timing model (byte times, return delays, the FTDI's 62-byte
packets and latency timer) against hand-computed known answers, the client's budget and read plan, late replies
dropped and counted, and the lockstep clock."""

from __future__ import annotations

import pytest

from op2motion.bus import protocol as p
from op2motion.bus.client import Bus
from op2motion.bus.clock import LockstepClock
from op2motion.bus.emulator.timing import INSTANT, USB_PAYLOAD_BYTES, TimedLink, WireTiming, packet_ends
from op2motion.bus.link import LinkBudget, read_plan, tick_spans
from op2motion.errors import InputError

BYTE_S = 10e-6                 # one byte at 1 Mbps (start, 8 data, stop bits)
TIME_TOL_S = 1e-9              # times computed from byte counts: exact but for floating point
IDS = tuple(range(1, 21))


def _echo_link(timing: WireTiming, delays: dict[int, int] | None = None, replies=None) -> tuple[TimedLink, list]:
    """A link whose devices answer every request with ``replies(request)`` (default: a status packet of the
    request's ID with 2 bytes); the requests it handed the devices, with their times."""
    seen: list[tuple[float, bytes]] = []

    def answer(t: float, request: bytes) -> list[bytes]:
        seen.append((t, request))
        return replies(request) if replies else [p.status(request[2], 0, b"\x00\x08")]

    return TimedLink(timing, answer, lambda d: (delays or {}).get(d, 0) * 2e-6), seen


def _deliveries(link: TimedLink, until: float, step: float = 1e-5) -> list[tuple[float, bytes]]:
    """Each USB packet the host receives up to ``until``, with the time it came."""
    out, t = [], 0.0
    while t < until:
        nxt = link.next_event()
        if nxt is None or nxt > until:
            break
        t = nxt
        out += [(t, b) for b in link.run_until(t)]
    return out


def test_one_read_costs_its_bytes_then_waits_for_the_latency_timer():
    link, seen = _echo_link(WireTiming(latency_timer_s=0.016))
    link.send(0.0, p.read(13, 36, 2))                       # 8 bytes out, 8 bytes back
    got = _deliveries(link, 0.1)
    assert seen[0][0] == pytest.approx(8 * BYTE_S, abs=TIME_TOL_S)            # the request's last byte
    assert len(got) == 1 and got[0][1] == p.status(13, 0, b"\x00\x08")
    assert got[0][0] == pytest.approx(0.016, abs=TIME_TOL_S)   # 160 µs on the wire, then held to the timer


def test_return_delay_and_a_one_ms_timer():
    link, _ = _echo_link(WireTiming(latency_timer_s=0.001), {13: 250})
    link.send(0.0, p.read(13, 36, 2))
    (t, _), = _deliveries(link, 0.1)
    assert t == pytest.approx(0.001, abs=TIME_TOL_S)        # 0.16 ms + 0.5 ms of return delay, then the timer
    link2, _ = _echo_link(WireTiming(latency_timer_s=0.001), {13: 254})
    link2.send(0.0008, p.read(13, 36, 2))                   # 0.8 ms + 0.16 + 0.508 ms: past the first firing
    (t2, _), = _deliveries(link2, 0.1)
    assert t2 == pytest.approx(0.002, abs=TIME_TOL_S)


def test_a_bulk_read_comes_in_62_byte_packets_and_its_tail_at_the_timer():
    spans = tick_spans(IDS, 1)                              # the loop's read: board, one full state, 19 positions
    chunk = b"".join(p.status(d, 0, bytes(n)) for d, _, n in spans)
    assert len(p.bulk_read(spans)) == 70 and len(chunk) == 202                 # bus_wire.md's figures

    link, seen = _echo_link(WireTiming(latency_timer_s=0.001), replies=lambda request: [chunk])
    link.send(0.0, p.bulk_read(spans))
    got = _deliveries(link, 0.1)
    sizes, times = [len(b) for _, b in got], [t for t, _ in got]
    assert sizes == [30, USB_PAYLOAD_BYTES, USB_PAYLOAD_BYTES, 48]   # the timer (1 ms) caught 30 bytes, then full
    assert times[0] == pytest.approx(0.001, abs=TIME_TOL_S)          # packets went at once, then the tail
    assert times[1] == pytest.approx(0.001 + USB_PAYLOAD_BYTES * BYTE_S, abs=TIME_TOL_S)
    assert times[2] == pytest.approx(0.001 + 2 * USB_PAYLOAD_BYTES * BYTE_S, abs=TIME_TOL_S)
    assert times[3] == pytest.approx(times[2] + 0.001, abs=TIME_TOL_S)   # the timer restarted at packet 3
    assert b"".join(b for _, b in got) == chunk
    assert (70 + 202) * BYTE_S == pytest.approx(0.00272)                     # 2.7 ms on the wire


def test_requests_queue_on_the_host_line_and_are_framed_by_packet():
    link, seen = _echo_link(INSTANT.__class__(latency_timer_s=0.001))
    both = p.write(13, 30, b"\x00\x08") + p.read(13, 36, 2)
    link.send(0.0, both[:5])                                # split anywhere: framed by LEN
    link.send(0.0, both[5:])
    _deliveries(link, 0.1)
    assert [r for _, r in seen] == [p.write(13, 30, b"\x00\x08"), p.read(13, 36, 2)]
    assert seen[0][0] == pytest.approx(9 * BYTE_S) and seen[1][0] == pytest.approx(17 * BYTE_S)
    assert packet_ends(b"\x00\xff\xff\xff\x01\x02\x01\xfb") == [8]           # noise and FF FF FF


def test_instant_wire_answers_at_once():
    link, seen = _echo_link(INSTANT)
    link.send(0.5, p.ping(13))
    assert link.next_event() is None and link.run_until(0.5) == [p.status(13, 0, b"\x00\x08")]


def test_timer_values_outside_the_chip_are_refused():
    with pytest.raises(InputError, match="latency timer of 1 to 255 ms"):
        WireTiming(latency_timer_s=0.0005)


def test_read_plan_from_the_budget():
    fast = LinkBudget(tail_s=0.0015)
    plan = read_plan(fast, IDS, 0.005)
    assert plan.servos_per_tick == 20 and plan.wire_s == pytest.approx(0.00272)      # bus_wire.md's 2.7 ms
    assert 10 <= read_plan(fast, IDS).servos_per_tick < 20                     # in its planned 3.5 ms: every 2 ticks
    slow = LinkBudget(tail_s=0.0015, delays_s={d: 250 * 2e-6 for d in IDS})
    reduced = read_plan(slow, IDS)
    assert 0 < reduced.servos_per_tick < 20 and reduced.tick_s <= 0.005
    assert read_plan(slow, IDS, 0.001).servos_per_tick == 0          # not even the board in 1 ms
    seen = [reduced.spans(k, IDS)[1] for k in range(40)]
    assert set(seen) == set(IDS)                                      # each servo's full state comes in turn
    read = [d for k in range(4) for d, _, _ in reduced.spans(k, IDS)[0] if d != 200]
    assert len(read) == len(set(read)) == 4 * reduced.servos_per_tick   # a window moving round the servos
    assert read_plan(LinkBudget(tail_s=0.017), IDS).servos_per_tick == 0    # a 16 ms timer: nothing fits


class ScriptedPort:
    """A port on a lockstep clock whose replies come when a script says (a device answering late)."""

    path = "scripted"
    latency_timer_ms = None
    low_latency = ""

    def __init__(self, script):
        self.clock = LockstepClock()
        self.script, self.pending, self.sent = script, [], []

    def write(self, data: bytes) -> None:
        self.sent.append(data)
        for delay, reply in self.script(len(self.sent), data):
            self.pending.append((self.clock.now() + delay, reply))

    def read(self, deadline: float) -> bytes:
        self.pending.sort(key=lambda x: x[0])
        if self.pending and self.pending[0][0] <= deadline:
            t, reply = self.pending.pop(0)
            self.clock.sleep_until(t)
            return reply
        self.clock.sleep_until(deadline)
        return b""

    def flush_input(self) -> bytes:
        due = [r for t, r in self.pending if t <= self.clock.now()]
        self.pending = [(t, r) for t, r in self.pending if t > self.clock.now()]
        return b"".join(due)

    def close(self) -> None:
        pass


def test_a_late_reply_is_dropped_and_counted_never_taken_for_the_next():
    old, new = p.status(13, 0, b"\x11\x11"), p.status(13, 0, b"\x22\x22")

    def script(n: int, request: bytes):
        if n == 1:
            return [(0.0015, old)]                  # the first read's reply comes 1.5 ms: after its wait
        return [(0.003, new)]

    port = ScriptedPort(script)
    bus = Bus(port, retries=0, margin_s=0.0)
    bus.link.tail_s = 0.001
    assert bus.read(13, 36, 2) is None              # given up after its wait (1.16 ms)
    bus.link.tail_s = 0.01                          # the next request waits long enough to see both replies
    reply = bus.read(13, 36, 2)
    assert reply is not None and reply.params == b"\x22\x22"
    assert bus.stats.stray == 1


def test_late_replies_of_a_bulk_read_never_answer_the_next():
    spans = [(200, 24, 2), (1, 36, 2), (2, 36, 2)]

    def script(n: int, request: bytes):
        delay = 0.004 if n == 1 else 0.0005          # the second tick's replies come after the first's late ones
        return [(delay, p.status(d, 0, bytes((n, n)))) for d, _, _ in spans]

    port = ScriptedPort(script)
    bus = Bus(port, retries=0, margin_s=0.0)
    bus.link.tail_s = 0.001
    assert bus.bulk_read(spans, 0.0) == {}                # all late: the wait ended at 1.1 ms
    port.clock.sleep_until(0.0038)                        # the next tick, just before the late replies come
    bus.link.tail_s = 0.003
    got = bus.bulk_read(spans, 0.0)
    assert {d: r.params for d, r in got.items()} == {d: b"\x02\x02" for d, _, _ in spans}
    assert bus.stats.stray == 3                           # the board's too: it came before any reply could


def test_a_retry_waits_out_the_late_window_so_its_reply_counts():
    def script(n: int, request: bytes):
        return [] if n == 1 else [(0.0002, p.status(13, 0, b"\x22\x22"))]

    port = ScriptedPort(script)
    bus = Bus(port, retries=1)
    bus.link.tail_s = 0.001
    reply = bus.read(13, 36, 2)
    assert reply is not None and reply.params == b"\x22\x22" and bus.stats.stray == 0 and bus.stats.retries == 1


def test_a_reply_with_error_bits_is_an_answer_asked_again_once_at_most():
    """A servo whose every reply carries all seven error bits is answered with them after one more try (the checksum
    and instruction bits may mean our packet arrived damaged), not given up on as silent; a damaged request that
    arrives whole the second time gets the clean reply; a call without retries takes the first reply as it is."""
    every = 0x7F

    def always(n: int, request: bytes):
        return [(0.0002, p.status(13, every, b"\x22\x22"))]

    port = ScriptedPort(always)
    bus = Bus(port, retries=3)
    reply = bus.read(13, 36, 2)
    assert reply is not None and reply.code == every and reply.params == b"\x22\x22"
    assert len(port.sent) == 2 and bus.stats.retries == 1 and bus.stats.device_errors == {13: 2}
    assert reply.errors == ("input voltage", "angle limit", "overheating", "range", "checksum", "overload",
                            "instruction")

    def once(n: int, request: bytes):
        return [(0.0002, p.status(13, p.CHECKSUM if n == 1 else 0, b"\x22\x22"))]

    port = ScriptedPort(once)
    reply = Bus(port, retries=3).read(13, 36, 2)
    assert reply is not None and reply.code == 0 and len(port.sent) == 2
    port = ScriptedPort(always)
    reply = Bus(port, retries=0).read(13, 36, 2)
    assert reply is not None and reply.code == every and len(port.sent) == 1


def test_lockstep_clock_runs_its_listeners_up_to_each_wait():
    clock, seen = LockstepClock(1.0), []
    clock.listen(seen.append)
    clock.sleep_until(1.5)
    clock.sleep_until(1.2)                          # never backwards
    assert seen == [1.5] and clock.now() == 1.5


def test_an_idle_adapter_reaches_any_time_in_bounded_steps():
    from op2motion.bus.emulator.timing import Ftdi

    for anchor in (0.1, 0.3, 1.7, 12.345):
        ftdi = Ftdi(0.001, BYTE_S, anchor)
        limit = anchor + 3 * 0.001                      # a firing exactly at the limit, in floating point
        steps = 0
        while ftdi.step(limit) is not None:
            steps += 1
            assert steps < 5
        assert ftdi.anchor == pytest.approx(limit)


def test_the_latency_timer_is_set_and_read_back_and_a_refusal_is_heard(tmp_path, monkeypatch):
    from op2motion.bus import port as port_module

    timer = tmp_path / "ttyUSB0" / "latency_timer"
    timer.parent.mkdir()
    timer.write_text("16\n")
    monkeypatch.setattr(port_module, "SYSFS_TIMER", str(tmp_path / "{name}" / "latency_timer"))

    class Refusing:
        def set_low_latency_mode(self, on: bool) -> None:
            raise OSError(25, "Inappropriate ioctl for device")

    value, said = port_module.low_latency(Refusing(), "/dev/ttyUSB0")
    assert value == 1 and timer.read_text() == "1"                       # written through sysfs, read back
    assert "ASYNC_LOW_LATENCY refused (Inappropriate ioctl for device)" in said and "wrote 1" in said
    assert port_module.sysfs_timer_path("/dev/ttyUSB3").endswith("/ttyUSB3/latency_timer")
