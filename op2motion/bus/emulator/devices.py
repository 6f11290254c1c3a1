"""The emulated devices' control tables, byte for byte: the CM-730 (ID 200) and one MX-28 per joint.

A :class:`Device` holds its table (:mod:`..tables`) and answers the instructions one device answers: a read of a
span, a write (a read-only byte, a value out of its register's range or a span beyond the table is a *range* error
and nothing is written; bytes between registers take what is written, as the framework's sync write of register
29 needs), the status error byte (the device's standing conditions plus the instruction's own error), and its status
return level (0: only pings, 1: pings and reads, 2: everything). A servo (:class:`Servo`) adds what its firmware
does with its registers: power-up defaults, the alarm shutdown (an error bit in ``alarm_shutdown`` switches the
torque off), the latched overload, the input-voltage and overheating conditions against its EEPROM limits.
"""

from __future__ import annotations

import struct

from op2motion.bus import protocol as p
from op2motion.bus.tables import CM730, CM730_ID, MX28, TORQUE_LIMIT_FULL, ControlTable

MIN_VOLTS, MAX_VOLTS = MX28["min_voltage_limit"].address, MX28["max_voltage_limit"].address
TEMPERATURE_LIMIT, ALARM_SHUTDOWN = MX28["temperature_limit"].address, MX28["alarm_shutdown"].address
TORQUE_ENABLE, MOVING, PRESENT = MX28["torque_enable"].address, MX28["moving"].address, MX28["present_position"].address
PRESENT_LAYOUT = struct.Struct("<HHHBB")          # present position, speed, load, voltage, temperature (36..43)

#: Largest value a writable register takes (others: what fits its size).
RANGES = {"torque_enable": 1, "p_gain": 254, "i_gain": 254, "d_gain": 254, "goal_position": 4095,
          "moving_speed": 1023, "torque_limit": TORQUE_LIMIT_FULL, "max_torque": TORQUE_LIMIT_FULL,
          "dynamixel_power": 1, "status_return_level": 2, "temperature_limit": 150, "cw_angle_limit": 4095,
          "ccw_angle_limit": 4095, "id": 253}


class Device:
    """One device on the bus: its ID, control table and bytes."""

    def __init__(self, device_id: int, table: ControlTable):
        self.id, self.spec = device_id, table
        self.table = table.defaults()
        self.table[table["id"].address] = device_id
        self.span = {r.name: (r.address, r.end) for r in table.registers}     # looked up hundreds of times a tick

    def u16(self, name: str) -> int:
        """A word register."""
        a = self.span[name][0]
        return self.table[a] | (self.table[a + 1] << 8)

    def set(self, name: str, value: int) -> None:
        """Set a register (the device itself, any access)."""
        a, end = self.span[name]
        self.table[a:end] = int(value).to_bytes(end - a, "little")

    def get(self, name: str) -> int:
        """A register's value."""
        a, end = self.span[name]
        return int.from_bytes(self.table[a:end], "little")

    @property
    def return_level(self) -> int:
        """The status return level."""
        return self.get("status_return_level")

    def conditions(self) -> int:
        """The standing error bits (none for a plain device)."""
        return 0

    def read(self, address: int, length: int) -> tuple[int, bytes | None]:
        """(error byte, the span) of a READ; a span beyond the table is a range error without data."""
        if length < 1 or address + length > self.spec.size:
            return self.conditions() | p.RANGE, None
        return self.conditions(), bytes(self.table[address:address + length])

    def write(self, address: int, data: bytes) -> int:
        """Apply a WRITE; its error byte."""
        end = address + len(data)
        if not data or end > self.spec.size:
            return self.conditions() | p.RANGE
        changes: dict[str, int] = {}
        for r in self.spec.registers:
            if r.end <= address or r.address >= end:
                continue
            if r.access != "RW":
                return self.conditions() | p.RANGE
            if r.address < address or r.end > end:                  # half a word: take the other half as it is
                merged = bytearray(self.table[r.address:r.end])
                for a in range(max(r.address, address), min(r.end, end)):
                    merged[a - r.address] = data[a - address]
                value = int.from_bytes(merged, "little")
            else:
                value = int.from_bytes(data[r.address - address:r.end - address], "little")
            if value > RANGES.get(r.name, (1 << (8 * r.size)) - 1):
                return self.conditions() | p.RANGE
            changes[r.name] = value
        self.table[address:end] = data
        for name, value in changes.items():
            self.changed(name, value)
        return self.conditions()

    def changed(self, name: str, value: int) -> None:
        """A register was written (the firmware's reaction)."""


class Board(Device):
    """The CM-730: the servos' power switch, LEDs, buttons, IMU and supply voltage."""

    def __init__(self) -> None:
        super().__init__(CM730_ID, CM730)
        self.power_changed = False

    def changed(self, name: str, value: int) -> None:
        if name == "dynamixel_power":
            self.power_changed = True


class Servo(Device):
    """One MX-28 (see the module docstring); the body (:mod:`.body`) fills its present-state registers."""

    def __init__(self, device_id: int):
        super().__init__(device_id, MX28)
        self.table[MX28["baud_rate"].address] = 1                  # the OP2's servos: 1 Mbps, no return delay
        self.table[MX28["return_delay_time"].address] = 0
        self.overloaded = False
        self.temperature_c = 0.0
        self.voltage_v = 0.0

    def power_up(self, present_ticks: int) -> None:
        """RAM to its power-up values: torque off, goal where the joint is, torque limit = max torque."""
        eeprom = bytes(self.table[:24])
        self.table[:] = MX28.defaults()
        self.table[:24] = eeprom
        self.set("goal_position", present_ticks)
        self.set("present_position", present_ticks)
        self.set("torque_limit", self.get("max_torque"))
        self.overloaded = False

    def conditions(self) -> int:
        error = 0
        volts, t = round(self.voltage_v * 10), self.table
        if not t[MIN_VOLTS] <= volts <= t[MAX_VOLTS]:
            error |= p.INPUT_VOLTAGE
        if self.temperature_c > t[TEMPERATURE_LIMIT]:
            error |= p.OVERHEATING
        if self.overloaded:
            error |= p.OVERLOAD
        return error

    def enforce_alarms(self) -> None:
        """The alarm shutdown: a standing condition in its mask switches the torque off."""
        if self.table[TORQUE_ENABLE] and self.conditions() & self.table[ALARM_SHUTDOWN]:
            self.table[TORQUE_ENABLE] = 0

    def present(self, ticks: int, speed: int, load: int, volts: int, celsius: int, moving: int) -> None:
        """The present-state registers (36..43 and 46) in one go: position, speed, load, voltage, temperature,
        moving."""
        self.table[PRESENT:PRESENT + 8] = PRESENT_LAYOUT.pack(ticks, speed, load, volts, celsius)
        self.table[MOVING] = moving

    def changed(self, name: str, value: int) -> None:
        if name == "torque_enable" and value == 1:
            self.overloaded = False                                 # re-enabling clears the latched overload
            self.enforce_alarms()
