"""The emulated servos' control tables side by side: one block of bytes, a row per servo, that each
:class:`~.devices.EmulatedServo` keeps its table in and that the body (:mod:`.body`) reads and fills for all the
servos at once through a NumPy view, instead of register by register and servo by servo.

What the bus sees is unchanged: a servo's table is its row, byte for byte; the body asks for the registers the motors
follow (goal, speed, P gain, torque limit, torque enable) as arrays and writes the present state (position, speed,
load, voltage, temperature, moving) as arrays.
"""

from __future__ import annotations

import numpy as np

from op2motion.bus import protocol as p
from op2motion.bus.emulator.devices import CCW_LIMIT, CW_LIMIT, GOAL, alarm_conditions, within_limits
from op2motion.bus.emulator.writeplan import WritePlan
from op2motion.bus.tables import MX28

#: The registers the motors follow (torque enable ... torque limit, the goal position among them): what the body's
#: drive depends on.
DRIVE_SPAN = (MX28["torque_enable"].address, MX28["torque_limit"].end)
GOAL_SPAN = (MX28["goal_position"].address, MX28["goal_position"].end)
WORD_WEIGHTS = np.array([1, 256])  # a little-endian word's bytes
MX28_MAX_TICK = MX28.limits["ccw_angle_limit"][1]      # 4095: the largest angle limit (and goal)


class ServoTables:
    """``count`` MX-28 control tables: :meth:`row` gives a servo its bytes, :meth:`column` a register of every
    servo."""

    def __init__(self, count: int):
        self.count = count
        self.data = bytearray(count * MX28.size)
        self.regs = np.frombuffer(self.data, dtype=np.uint8).reshape(count, MX28.size)   # a view: writes go through
        self.columns = {r.name: self.regs[:, r.address] if r.size == 1 else
                        self.regs[:, r.address:r.end].view("<u2")[:, 0] for r in MX28.registers}
        full = (0).to_bytes(2, "little") + (MX28_MAX_TICK).to_bytes(2, "little")     # cw 0, ccw 4095
        self._full_limits = full * count

    def row(self, index: int) -> memoryview:
        """Servo ``index``'s table (a view of its row)."""
        return memoryview(self.data)[index * MX28.size:(index + 1) * MX28.size]

    def column(self, name: str) -> np.ndarray:
        """Register ``name`` of every servo (count,): bytes as uint8, words (little-endian) as uint16; a view
        (assigning to it writes the registers)."""
        return self.columns[name]

    def drive_keys(self) -> tuple[bytes, bytes]:
        """Every servo's registers the motors follow (:data:`DRIVE_SPAN`) as two keys, the goals' and the others':
        equal keys, equal drives (the goals change every tick, the others seldom)."""
        regs = self.regs
        return (regs[:, GOAL_SPAN[0]:GOAL_SPAN[1]].tobytes(),
                regs[:, DRIVE_SPAN[0]:GOAL_SPAN[0]].tobytes() + regs[:, GOAL_SPAN[1]:DRIVE_SPAN[1]].tobytes())

    def put_present(self, ticks: np.ndarray, speed: np.ndarray, load: np.ndarray, volts: int, celsius: np.ndarray,
                    moving: np.ndarray) -> None:
        """Every servo's present-state registers (36..43 and 46): position [tick], speed and load (register values),
        voltage [0.1 V], temperature [°C], moving (0/1)."""
        c = self.columns
        c["present_position"][:], c["present_speed"][:], c["present_load"][:] = ticks, speed, load
        c["present_voltage"][:], c["present_temperature"][:], c["moving"][:] = volts, celsius, moving

    def enforce_alarms(self, volts: int, celsius: np.ndarray, overloaded: np.ndarray | bool) -> None:
        """Every servo's alarm shutdown (:meth:`.devices.EmulatedServo.enforce_alarms`) at once: ``volts`` [0.1 V],
        ``celsius`` (count,) [°C], ``overloaded`` (count,) bool (or False: none is)."""
        c = self.columns
        errors = alarm_conditions(volts, c["min_voltage_limit"], c["max_voltage_limit"], celsius,
                                  c["temperature_limit"], overloaded)
        if not np.count_nonzero(errors):                # np.count_nonzero: the fastest any() there is
            return
        torque = c["torque_enable"]
        torque[(torque != 0) & ((errors & c["alarm_shutdown"]) != 0)] = 0

    def put(self, rows: np.ndarray, address: int, data: np.ndarray, plan: WritePlan) -> None:
        """A WRITE nobody answers (a sync write's) of ``data`` (len(rows), length) at ``address`` to the servos at
        ``rows`` (each once), as :meth:`.devices.EmulatedServo.put` does it to each: ``plan`` (the span's, with no
        reactions) refuses a row with a value out of range; a goal out of the angle limits is clipped to the nearest
        one and raises the alarm."""
        if plan.refused:
            return
        ok = self._in_range(data, plan)
        if not ok.all():
            rows, data = rows[ok], data[ok]
        self.regs[rows, address:address + data.shape[1]] = data
        if not address <= GOAL.address < address + data.shape[1] or self._full_range():
            return                          # no goal written, or every goal within 0..4095 already is within limits
        c = self.columns
        goal = c["goal_position"]
        asked = goal[rows]
        clipped = within_limits(asked, c["cw_angle_limit"][rows], c["ccw_angle_limit"][rows])
        off = clipped != asked
        if np.count_nonzero(off):
            goal[rows[off]] = clipped[off]
            alarmed = rows[off][(c["alarm_shutdown"][rows[off]] & p.ANGLE_LIMIT) != 0]
            c["torque_enable"][alarmed] = 0

    def _in_range(self, data: np.ndarray, plan: WritePlan) -> np.ndarray:
        """Which rows of ``data`` the ``plan``'s value ranges take (count,) bool."""
        ok = np.ones(len(data), dtype=bool)
        for start, end, low, high in plan.checks:
            value = data[:, start] if end - start == 1 else data[:, start:end].astype(np.int64) @ WORD_WEIGHTS
            if low > 0:
                ok &= value >= low
            if high < (1 << (8 * (end - start))) - 1:           # else the bytes cannot hold more
                ok &= value <= high
        return ok

    def _full_range(self) -> bool:
        """Whether every servo's angle limits are 0 and 4095 (joint mode over the whole circle: a goal the range
        check let through is within them)."""
        return self.regs[:, CW_LIMIT.address:CCW_LIMIT.end].tobytes() == self._full_limits
