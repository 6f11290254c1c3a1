"""The emulated devices' control tables, byte for byte: the CM-730 (ID 200) and one MX-28 per joint.

A :class:`Device` holds its table (:mod:`..tables`) and answers what one device answers: a READ of a span (one
beyond the table is a range error without data: the CM-730 firmware does not check a READ's span and sends whatever
memory follows its table, which the emulator does not make up), a WRITE, its status error byte (the standing
conditions as the instruction arrived, plus the instruction's own error) and its status return level (0: only
pings, 1: and reads, 2: all).

A WRITE is checked as the CM-730 firmware checks it (``WriteControlTableRangeCheck`` of ``CM_DXL_COM.c``) before
anything is written: a span beyond the table, one starting on the high byte of a word or ending on its low byte,
a read-only register, or a value out of its register's range (:attr:`..tables.ControlTable.limits`) is a range
error and nothing is written. Bytes of no register take what is written on the MX-28 (the framework's sync write
covers its byte 29) and are refused on the CM-730 (its firmware's range table makes them read-only).

The :class:`Board` (CM-730) switches the servos' power (register 24) and has no REG_WRITE (its firmware answers it, and
ACTION, with the instruction error). It plays the OP2's CM-740 too (:func:`.faults.with_board`): the e-manual gives the
CM-740 the CM-730's control table; what differs is the model number it reports. An :class:`EmulatedServo` (MX-28) adds
what its firmware does with its registers: power-up defaults, the alarm shutdown (an error bit in ``alarm_shutdown``
switches the torque off), the latched overload, the input-voltage and overheating conditions against its EEPROM limits,
REG_WRITE and ACTION (Registered, address 44, is 1 while a write waits; ACTION without one is an instruction error:
Protocol 1.0 e-manual), and the angle limits below.

Angle limits (MX-28 e-manual: the CW / CCW angle limit is the smallest / largest goal position; a goal out of that
range sets the angle-limit error bit and triggers the alarm as set in alarm LED / shutdown). In joint mode (the two
limits not both 0 (wheel mode) nor both 4095 (multi-turn mode)) a goal out of the limits sets bit 1 (value 2) in the
reply and is applied clipped to the nearest limit: the e-manual says the limits restrain the motion but not what the
register then holds, and the CM-730 firmware, built on the servos' code, still applies a write whose check gave any
error but the range error. The emulator keeps the clipped goal so that the body, which drives to the register, stops
at the limit as the servo does.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from op2motion.bus import protocol as p
from op2motion.bus.emulator.writeplan import WritePlan, write_plan
from op2motion.bus.tables import CM730, CM730_ID, MX28, ControlTable

MIN_VOLTS, MAX_VOLTS = MX28["min_voltage_limit"].address, MX28["max_voltage_limit"].address
TEMPERATURE_LIMIT, ALARM_SHUTDOWN = MX28["temperature_limit"].address, MX28["alarm_shutdown"].address
TORQUE_ENABLE = MX28["torque_enable"].address
GOAL, CW_LIMIT, CCW_LIMIT = MX28["goal_position"], MX28["cw_angle_limit"], MX28["ccw_angle_limit"]
EEPROM_END = MX28["torque_enable"].address        # 24: the EEPROM area (kept over power cycles) ends
WHEEL_MODE = (0, 0)                               # CW and CCW angle limits both 0
MULTI_TURN_MODE = (4095, 4095)                    # ... both 4095


class Device:
    """One device on the bus: its ID, control table and bytes (``storage``: the bytes to keep the table in, e.g. a
    row of :class:`.bank.ServoTables`; default its own)."""

    reacts_to: frozenset[str] = frozenset()          # the registers whose writing the firmware reacts to (changed)

    def __init__(self, device_id: int, table: ControlTable, storage: memoryview | None = None):
        self.id, self.spec = device_id, table
        self.table: bytearray | memoryview = table.defaults()
        if storage is not None:
            storage[:] = self.table
            self.table = storage
        self.table[table["id"].address] = device_id
        self.span = {r.name: (r.address, r.end) for r in table.registers}     # looked up hundreds of times a tick
        self._level_at = table["status_return_level"].address
        self._delay_at = table["return_delay_time"].address
        self._plans: dict[tuple[int, int], WritePlan] = {}

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
        return self.table[self._level_at]

    @property
    def return_delay(self) -> int:
        """The Return Delay Time register [2 µs]."""
        return self.table[self._delay_at]

    def conditions(self) -> int:
        """The standing error bits (none for a plain device)."""
        return 0

    def read(self, address: int, length: int) -> tuple[int, bytes | None]:
        """(error byte, the span) of a READ; a span beyond the table is a range error without data."""
        if length < 1 or address + length > self.spec.size:
            return self.conditions() | p.RANGE, None
        return self.conditions(), bytes(self.table[address:address + length])

    def check(self, address: int, data: bytes) -> int:
        """The range error a WRITE of ``data`` at ``address`` gets (0: none; see the module docstring)."""
        plan = self.plan(address, len(data))
        if plan.refused:
            return p.RANGE
        for start, end, low, high in plan.checks:
            value = data[start] if end - start == 1 else int.from_bytes(data[start:end], "little")
            if not low <= value <= high:
                return p.RANGE
        return 0

    def plan(self, address: int, length: int) -> WritePlan:
        """The :class:`WritePlan` of a WRITE of ``length`` bytes at ``address`` (worked out on first use)."""
        plan = self._plans.get((address, length))
        if plan is None:
            plan = self._plans[(address, length)] = write_plan(self.spec, self.reacts_to, address, length)
        return plan

    def verdict(self, address: int, data: bytes) -> int:
        """The error bits a WRITE of ``data`` at ``address`` gets, without writing (a plain device: the range)."""
        return self.check(address, data)

    def write(self, address: int, data: bytes) -> int:
        """Apply a WRITE unless it is refused with a range error; its error byte (the conditions as it arrived)."""
        standing = self.conditions()
        return standing | self.put(address, data)

    def put(self, address: int, data: bytes) -> int:
        """:meth:`write` without the standing conditions (what a write nobody answers needs): the write's own error
        bits."""
        error = self.verdict(address, data)
        if not error & p.RANGE:
            self.apply(address, data)
        return error

    def apply(self, address: int, data: bytes) -> None:
        """Write checked bytes; the firmware reacts to the registers written (:attr:`reacts_to`)."""
        self.table[address:address + len(data)] = data
        for name, start, end in self.plan(address, len(data)).reactions:
            self.changed(name, int.from_bytes(self.table[start:end], "little"))

    def changed(self, name: str, value: int) -> None:
        """A register was written (the firmware's reaction)."""


class Board(Device):
    """The CM-730 (the CM-740 once its model number is set): the servos' power switch, LEDs, buttons, IMU and supply
    voltage."""

    reacts_to = frozenset({"dynamixel_power"})

    def __init__(self) -> None:
        super().__init__(CM730_ID, CM730)
        self.power_changed = False

    def changed(self, name: str, value: int) -> None:
        if name == "dynamixel_power":
            self.power_changed = True

    def cold_start(self) -> None:
        """The board just switched on: its writable RAM registers at their power-on values (the servos' power off,
        the LEDs as the firmware's ``ProcessInit`` sets them); the sensors keep what they measure."""
        for r in CM730.registers:
            if r.area == "RAM" and r.access == "RW":
                self.set(r.name, r.default or 0)
        self.power_changed = False


class EmulatedServo(Device):
    """One MX-28 (see the module docstring); the body (:mod:`.body`) fills its present-state registers
    (``storage``: its row of the servos' tables, :class:`.bank.ServoTables`)."""

    reacts_to = frozenset({"torque_enable"})

    def __init__(self, device_id: int, storage: memoryview | None = None):
        super().__init__(device_id, MX28, storage)
        self.table[MX28["baud_rate"].address] = 1                  # the OP2's servos: 1 Mbps, no return delay
        self.table[MX28["return_delay_time"].address] = 0
        self.overloaded = False
        self.temperature_c = 0.0
        self.voltage_v = 0.0
        self.waiting: tuple[int, bytes] | None = None              # a REG_WRITE's (address, data) until ACTION

    def power_up(self, present_ticks: int) -> None:
        """RAM to its power-up values: torque off, goal where the joint is, torque limit = max torque, nothing
        registered."""
        eeprom = bytes(self.table[:EEPROM_END])
        self.table[:] = MX28.defaults()
        self.table[:EEPROM_END] = eeprom
        self.set("goal_position", present_ticks)
        self.set("present_position", present_ticks)
        self.set("torque_limit", self.get("max_torque"))
        self.overloaded = False
        self.waiting = None

    def power_off(self) -> None:
        """Its supply switched off: no torque, and a registered write is lost with the RAM."""
        self.set("torque_enable", 0)
        self.set("registered", 0)
        self.waiting = None

    def conditions(self) -> int:
        t = self.table
        return int(alarm_conditions(round(self.voltage_v * 10), t[MIN_VOLTS], t[MAX_VOLTS], self.temperature_c,
                                    t[TEMPERATURE_LIMIT], self.overloaded))

    def enforce_alarms(self) -> None:
        """The alarm shutdown: a standing condition in its mask switches the torque off."""
        if self.table[TORQUE_ENABLE] and self.conditions() & self.table[ALARM_SHUTDOWN]:
            self.table[TORQUE_ENABLE] = 0

    def changed(self, name: str, value: int) -> None:
        if name == "torque_enable" and value == 1:
            self.overloaded = False                                 # re-enabling clears the latched overload
            self.enforce_alarms()

    def verdict(self, address: int, data: bytes) -> int:
        """The range error, or the angle-limit error of a goal out of the limits as they will be after the write."""
        error = self.check(address, data)
        if error or not address <= GOAL.address < address + len(data):
            return error
        if address < CCW_LIMIT.end and CW_LIMIT.address < address + len(data):    # the limits written too
            after: bytearray | memoryview = bytearray(self.table)
            after[address:address + len(data)] = data
        else:
            after = self.table
        at = GOAL.address - address                  # a whole word: half a one is refused above
        goal = data[at] | (data[at + 1] << 8)
        return p.ANGLE_LIMIT if _clipped(after, goal) != goal else 0

    def apply(self, address: int, data: bytes) -> None:
        """Write; a goal out of the angle limits (joint mode) is clipped to the nearest one and raises the alarm."""
        super().apply(address, data)
        if not address <= GOAL.address < address + len(data):
            return
        goal = self.u16("goal_position")
        clipped = _clipped(self.table, goal)
        if clipped != goal:
            self.set("goal_position", clipped)
            if self.table[ALARM_SHUTDOWN] & p.ANGLE_LIMIT:
                self.table[TORQUE_ENABLE] = 0

    def reg_write(self, address: int, data: bytes) -> int:
        """REG_WRITE: keep the write for ACTION (Registered = 1) unless it is refused; its error byte (the errors
        the write will get)."""
        standing = self.conditions()
        error = self.verdict(address, data)
        if not error & p.RANGE:
            self.waiting = (address, bytes(data))
            self.set("registered", 1)
        return standing | error

    def action(self) -> int:
        """ACTION: apply the registered write and clear Registered; without one, the instruction error."""
        if self.waiting is None:
            return self.conditions() | p.INSTRUCTION
        (address, data), self.waiting = self.waiting, None
        self.set("registered", 0)
        return self.write(address, data)


def _clipped(table: bytearray | memoryview, goal: int) -> int:
    """``goal`` within the angle limits of ``table`` (:func:`within_limits`)."""
    cw = table[CW_LIMIT.address] | (table[CW_LIMIT.address + 1] << 8)
    ccw = table[CCW_LIMIT.address] | (table[CCW_LIMIT.address + 1] << 8)
    return int(within_limits(goal, cw, ccw))


def within_limits(goal: Any, cw: Any, ccw: Any) -> Any:
    """``goal`` [tick] within the angle limits ``cw``..``ccw`` in joint mode, as it is in wheel and multi-turn mode
    (see the module docstring). Of one servo (numbers) or of several (arrays, :mod:`.bank`)."""
    joint = (((cw != WHEEL_MODE[0]) | (ccw != WHEEL_MODE[1]))
             & ((cw != MULTI_TURN_MODE[0]) | (ccw != MULTI_TURN_MODE[1])))
    return np.where(joint, np.minimum(np.maximum(goal, cw), ccw), goal)


def alarm_conditions(volts: Any, min_volts: Any, max_volts: Any, celsius: Any, limit_c: Any, overloaded: Any) -> Any:
    """A servo's standing error bits: the input voltage [0.1 V] outside its limits, the temperature [°C] above its
    limit, the latched overload. Of one servo (numbers) or of several (arrays, :mod:`.bank`)."""
    return (((volts < min_volts) | (volts > max_volts)) * p.INPUT_VOLTAGE | (celsius > limit_c) * p.OVERHEATING
            | overloaded * p.OVERLOAD)
