"""The emulated OP2's fast paths do what the one-by-one rules do: a sync write to all the servos' tables at once, the
alarms of all the servos at once, the speed and load registers of all the servos at once, the FTDI's next packet
worked out (and kept) without stepping a copy, the body's drive kept until its registers change."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from op2motion.bus import protocol as p
from op2motion.bus.emulator.faults import Faults
from op2motion.bus.emulator.timing import USB_PAYLOAD_BYTES, Ftdi
from op2motion.bus.emulator.wire import BOOT_S, Wire
from op2motion.bus.tables import CM730, CM730_ID, MX28, magnitude, magnitudes

JOINT_TICKS = 2048             # every joint's position (a powering-up servo's goal)
SUPPLY_V = 12.0                # within the servos' voltage limits
ROUNDS = 40                    # random sync writes compared
BYTE_S = 10e-6                 # one byte at 1 Mbps
IDS = list(range(1, 21))


def _wire(spec) -> Wire:
    """A wire with the servos powered and booted (no physics: the joints stand still)."""
    t = [1.0]
    wire = Wire(spec, Faults(), now=lambda: t[0], present_ticks=lambda: [JOINT_TICKS] * 20)
    for servo in wire.servos:
        servo.voltage_v = SUPPLY_V
    wire.feed(p.write(CM730_ID, CM730["dynamixel_power"].address, b"\x01"))
    t[0] += BOOT_S
    return wire


def _tables(wire: Wire) -> bytes:
    return b"".join(bytes(s.table) for s in wire.servos) + bytes(wire.board.table)


def _limits(wire: Wire, rng: np.random.Generator) -> None:
    """Angle limits and alarm masks of every kind: joint mode (narrow and whole), wheel and multi-turn mode."""
    for servo in wire.servos:
        cw, ccw = [(0, 4095), (1000, 3000), (0, 0), (4095, 4095), (2500, 2600)][int(rng.integers(5))]
        servo.table[MX28["cw_angle_limit"].address:MX28["cw_angle_limit"].end] = p.word_bytes(cw)
        servo.table[MX28["ccw_angle_limit"].address:MX28["ccw_angle_limit"].end] = p.word_bytes(ccw)
        servo.set("alarm_shutdown", int(rng.choice([0, p.ANGLE_LIMIT, 0x24])))
        servo.set("torque_enable", 1)


def _chunk(address: int, length: int, rng: np.random.Generator) -> bytes:
    """``length`` bytes from ``address``: mostly in range, sometimes a gain of 255 or a goal beyond 4095."""
    data = bytearray(rng.integers(0, 60, length, dtype=np.uint8).tobytes())
    for r in MX28.registers:
        if address <= r.address and r.end <= address + length and r.size == 2:
            high = 5000 if rng.random() < 0.1 else 4095 if r.name == "goal_position" else 1023
            data[r.address - address:r.end - address] = p.word_bytes(int(rng.integers(0, high + 1)))
    if rng.random() < 0.1:
        data[int(rng.integers(length))] = 255
    return bytes(data)


@pytest.mark.parametrize("address,length", [(26, 6), (30, 2), (32, 4), (28, 4), (12, 2), (24, 1)])
def test_a_sync_write_to_all_servos_at_once_is_the_one_by_one_write(spec, rng, address, length):
    fast, slow = _wire(spec), _wire(spec)
    _limits(fast, np.random.default_rng(7))
    _limits(slow, np.random.default_rng(7))
    for _ in range(ROUNDS):
        ids = [int(d) for d in rng.choice(IDS, int(rng.integers(1, 21)), replace=False)]
        packet = p.sync_write(address, length, {d: _chunk(address, length, rng) for d in ids})
        params = packet[5:-1]
        fast._sync_write(params)
        slow._write_each(params)                       # the writes one by one, as the firmware takes them
        assert _tables(fast) == _tables(slow)
    assert any(s.get("torque_enable") == 0 for s in fast.servos) or address != 26    # an alarm did shut one down


def test_the_alarms_of_all_servos_at_once_are_each_servos(spec, rng):
    celsius = rng.uniform(60.0, 100.0, 20)
    overloaded = rng.random(20) < 0.2
    wires = []
    for _ in range(2):
        wire = _wire(spec)
        _limits(wire, np.random.default_rng(11))
        for servo, c, o in zip(wire.servos, celsius, overloaded):
            servo.temperature_c, servo.overloaded = float(c), bool(o)
        wires.append(wire)
    at_once, one_by_one = wires
    at_once.tables.enforce_alarms(round(SUPPLY_V * 10), celsius, overloaded)
    for servo in one_by_one.servos:
        servo.enforce_alarms()
    after = [s.get("torque_enable") for s in at_once.servos]
    assert after == [s.get("torque_enable") for s in one_by_one.servos] and 0 < sum(after) < 20


def test_the_speed_and_load_registers_of_all_servos_are_each_ones(rng):
    values = np.concatenate([rng.normal(0.0, 600.0, 500), [0.0, -0.0, 0.5, -0.5, 0.5000001, -0.5000001, 1.5, -1.5,
                                                           1022.5, -1023.5, 1e6, -1e6]])
    assert magnitudes(values).tolist() == [magnitude(v) for v in values.tolist()]


def _reference_next_packet(ftdi: Ftdi) -> float | None:
    """When a copy of the chip, stepped with nothing more arriving, sends its first packet with bytes in it."""
    twin = copy.deepcopy(ftdi)
    while (event := twin.step(math.inf)) is not None:
        if event[1]:
            return event[0]
    return None


def test_the_next_packet_is_what_stepping_a_copy_finds_and_is_kept_only_while_nothing_changes(rng):
    for timer_s in (0.001, 0.016):
        ftdi = Ftdi(timer_s, BYTE_S, float(rng.uniform(0.0, 1.0)))
        t = ftdi.anchor
        for _ in range(300):
            if rng.random() < 0.3:                      # replies back to back, a little later
                start = t + float(rng.uniform(0.0, 0.002))
                for _ in range(int(rng.integers(1, 22))):
                    size = int(rng.integers(6, 40))
                    ftdi.receive(start + BYTE_S, bytes(size))
                    start += size * BYTE_S
            assert ftdi.next_packet() == _reference_next_packet(ftdi)
            t += float(rng.uniform(0.0, 0.003))
            sent = ftdi.run(t)
            assert all(0 < len(payload) <= USB_PAYLOAD_BYTES for payload in sent)


@pytest.mark.physics
def test_the_drive_is_kept_until_its_registers_change_and_is_then_the_registers(spec, rng):
    from op2motion.bus.emulator.server import Emulator

    emulator = Emulator(spec, "mujoco")
    try:
        body, tables = emulator.body, emulator.wire.tables
        for _ in range(30):
            name = str(rng.choice(["goal_position", "moving_speed", "p_gain", "torque_limit", "torque_enable"]))
            servo = emulator.servos[int(rng.integers(20))]
            servo.set(name, int(rng.integers(0, 2 if name == "torque_enable" else 255)))
            powered = bool(rng.random() < 0.9)
            kept, fresh = body.drive(tables, powered), body._new_drive(tables, powered)
            assert all(np.array_equal(a, b) for a, b in zip(kept, fresh))
            assert body.drive(tables, powered) is kept                   # nothing changed: the same drive
    finally:
        emulator.close()
