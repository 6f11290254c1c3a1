"""The OP2 on its bus: the CM-730 at ID 200 (the servos' power switch, buttons, supply voltage, IMU) and the 20
MX-28 (torque, gains, goal, moving speed, torque limit, present position/speed/load/voltage/temperature, error bits by
name), through a :class:`~.client.Bus`.

:meth:`OP2.connect` finds the board (nothing at ID 200 is bad input naming ``--port``: exit 2), reads its model
number (neither a CM-730's nor a CM-740's: :class:`~.safety.WrongModel`, exit 2, nothing written), measures the link
(:func:`~.link.measure_link`: the ping round trip, the USB adapter's tail) and switches the servos' power on as the
framework does (write 1 to register 24, then wait :data:`POWER_ON_WAIT_S`; a servo is silent until powered).
:meth:`OP2.status` reads the board and every servo in full. :meth:`OP2.take_control` switches the torque on without a
jump: every goal is first set to where the joint is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from op2motion.bus.client import DAMAGED, Bus
from op2motion.bus.clock import sleep
from op2motion.bus.link import LinkCheck, ReadPlan, measure_link, return_delays
from op2motion.bus.realtime import LOOP_PRIORITY, realtime
from op2motion.bus.safety import WrongModel, board_model_problem
from op2motion.bus.tables import (
    CM730,
    CM730_ID,
    MX28,
    SPEED_RAD_S_PER_UNIT,
    TORQUE_LIMIT_FULL,
    VOLTS_PER_UNIT,
    model_name,
    signed,
)
from op2motion.errors import CheckFailed, InputError, shown
from op2motion.jsonout import JsonObject
from op2motion.robot.framework import DEFAULT_P_GAIN
from op2motion.robot.imu import GYRO_SAMPLES, attitude, decode_span, gyro_centres, imu_of
from op2motion.robot.joints import servo_to_ticks, ticks_to_servo
from op2motion.robot.spec import Spec

POWER_ON_WAIT_S = 0.3              # the framework's wait after switching the servos' power on (CM730::DXLPowerOn)
BOARD_READ = (0, CM730["voltage"].end)             # the board's table up to the supply voltage (0..50)
SERVO_READ = (0, MX28["present_temperature"].end)  # a servo's table up to its temperature (0..43): every register
                                                   # the status needs, none a firmware might leave out


@dataclass(frozen=True)
class BoardState:
    """The sub-controller: model number, firmware, the servos' power, supply [V], buttons, the IMU (torso frame:
    gyro [rad/s], accelerometer [m/s²]) and the attitude it implies [rad], the raw IMU words, and its error bits."""

    model_number: int
    firmware: int
    power: bool
    voltage_v: float
    buttons: int
    gyro_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    pitch_rad: float
    roll_rad: float
    tilt_rad: float
    words: dict[int, int]
    errors: tuple[str, ...]
    return_delay: int = 0

    def as_dict(self) -> JsonObject:
        """JSON-ready (angles in degrees)."""
        return {"id": CM730_ID, "model_number": self.model_number,
                "model": model_name(self.model_number) or f"model {self.model_number:#06x}",
                "firmware": self.firmware, "power": self.power,
                "return_delay_us": self.return_delay * 2,
                "voltage_v": round(self.voltage_v, 1), "buttons": self.buttons,
                "gyro_rad_s": [round(float(v), 4) for v in self.gyro_rad_s],
                "accel_m_s2": [round(float(v), 3) for v in self.accel_m_s2],
                "pitch_deg": round(math.degrees(self.pitch_rad), 1), "roll_deg": round(math.degrees(self.roll_rad), 1),
                "tilt_deg": round(math.degrees(self.tilt_rad), 1), "errors": list(self.errors)}


@dataclass(frozen=True)
class ServoState:
    """One MX-28 as read in full: which joint, whether it answered, and its registers in SI units (angles [rad],
    speed [rad/s], load as a share of its most torque, voltage [V], temperature [°C])."""

    id: int
    joint: str
    answers: bool
    model_number: int = 0
    firmware: int = 0
    return_level: int = 2
    temperature_limit_c: int = 0
    alarm_shutdown: int = 0
    torque_on: bool = False
    p_gain: int = 0
    goal_rad: float = 0.0
    moving_speed: int = 0
    torque_limit: int = 0
    position_rad: float = 0.0
    speed_rad_s: float = 0.0
    load: float = 0.0
    voltage_v: float = 0.0
    temperature_c: int = 0
    errors: tuple[str, ...] = field(default=())
    return_delay: int = 0

    def as_dict(self) -> JsonObject:
        """JSON-ready (angles in degrees)."""
        if not self.answers:
            return {"id": self.id, "joint": self.joint, "answers": False}
        return {"id": self.id, "joint": self.joint, "answers": True, "model_number": self.model_number,
                "model": model_name(self.model_number) or f"model {self.model_number}",
                "firmware": self.firmware, "return_delay_us": self.return_delay * 2,
                "position_deg": round(math.degrees(self.position_rad), 2),
                "goal_deg": round(math.degrees(self.goal_rad), 2),
                "speed_deg_s": round(math.degrees(self.speed_rad_s), 1), "load": round(self.load, 3),
                "voltage_v": round(self.voltage_v, 1), "temperature_c": self.temperature_c,
                "temperature_limit_c": self.temperature_limit_c, "torque_on": self.torque_on,
                "p_gain": self.p_gain, "torque_limit": self.torque_limit, "errors": list(self.errors)}


class NoBoard(InputError):
    """Nothing answers at ID 200: not an OP2's port, or the robot is off."""


def angle_of(tick: int, spec: Spec) -> float:
    """A position register's servo angle [rad]."""
    return float(ticks_to_servo(np.asarray(tick), spec))


def _u16(data: bytes, address: int, start: int = 0) -> int:
    return data[address - start] | (data[address - start + 1] << 8)


class OP2:
    """The robot on a bus (see the module docstring)."""

    def __init__(self, bus: Bus, spec: Spec):
        self.bus, self.spec = bus, spec
        self.imu = imu_of(spec)
        self.ids = tuple(j.id for j in spec.joints)
        self.joint_of = {j.id: j.name for j in spec.joints}
        self.return_level: dict[int, int] = {}
        self.gyro_centre: dict[int, float] | None = None
        self.link: LinkCheck | None = None
        self.plan: ReadPlan | None = None               # what the loop reads a tick, as tried before a motion

    # --- the board -------------------------------------------------------------------------------------------
    def connect(self, power: bool = True) -> None:
        """Find the board at ID 200 and (with ``power``) switch the servos' power on."""
        port = self.bus.port
        if self.bus.ping(CM730_ID) is None:
            raise NoBoard(f"nothing answers at ID {CM730_ID} on {shown(port.path)} (expected the OP2's CM-730 "
                          f"sub-controller: is this the robot's port, and is the robot switched on?)", "port")
        self.check_board_model()
        with realtime(LOOP_PRIORITY):                   # the loop's priority: the PC's load is not the link's
            self.link = measure_link(self.bus, CM730_ID, port.latency_timer_ms, port.low_latency)
        if power:
            self.power_on()

    def check_board_model(self) -> int:
        """The board's model number, read before anything is written to it; refused (:class:`~.safety.WrongModel`,
        exit 2) unless a CM-730's or a CM-740's."""
        register = CM730["model_number"]
        reply = self.bus.read(CM730_ID, register.address, register.size)
        if reply is None:
            raise CheckFailed(f"the sub-controller (ID {CM730_ID}) answers a ping but not a read of its model number")
        model = _u16(reply.params, 0)
        problem = board_model_problem(model)
        if problem is not None:
            raise WrongModel(problem.describe())
        return model

    def power_on(self) -> bool:
        """Switch the servos' power on if it is off, and wait for them to boot; True if it was off."""
        reply = self.bus.read(CM730_ID, CM730["dynamixel_power"].address, 1)
        if reply is not None and reply.params[0] == 1:
            return False
        self.bus.write(CM730_ID, CM730["dynamixel_power"].address, b"\x01")
        sleep(self.bus.clock, POWER_ON_WAIT_S)
        return True

    def board(self) -> BoardState | None:
        """The board's table read in full (None if it does not answer)."""
        start, end = BOARD_READ
        reply = self.bus.read(CM730_ID, start, end - start)
        if reply is None:
            return None
        data = reply.params
        gyro, accel = decode_span(self.imu, data, start)
        pitch, roll, tilt = attitude(accel)
        words = {c.register: _u16(data, c.register, start) for c in (*self.imu.gyro, *self.imu.accel)}
        delay = data[CM730["return_delay_time"].address]
        return_delays(self.bus.link, {CM730_ID: delay})
        return BoardState(_u16(data, 0, start), data[2], data[CM730["dynamixel_power"].address] == 1,
                          data[CM730["voltage"].address] * VOLTS_PER_UNIT, data[CM730["button"].address], gyro, accel,
                          pitch, roll, tilt, words, reply.errors, delay)

    def calibrate_gyro(self, samples: int = GYRO_SAMPLES) -> dict[int, float] | None:
        """Measure the gyro's zero-rate counts while the robot is still (:func:`~.imu.gyro_centres`); kept in
        :attr:`gyro_centre` for the loop (None, the nominal centre, if the robot moved or the board is silent)."""
        registers = [c.register for c in self.imu.gyro]
        start, end = min(registers), max(registers) + 2
        words = []
        for _ in range(samples):
            reply = self.bus.read(CM730_ID, start, end - start, retries=0)
            if reply is not None:
                words.append({r: _u16(reply.params, r, start) for r in registers})
        self.gyro_centre = gyro_centres(self.imu, words) if len(words) >= samples // 2 else None
        return self.gyro_centre

    # --- the servos ------------------------------------------------------------------------------------------
    def servo(self, device: int) -> ServoState:
        """One servo's table read in full."""
        start, end = SERVO_READ
        reply = self.bus.read(device, start, end - start)
        joint = self.joint_of.get(device, f"id {device}")
        if reply is None:
            return ServoState(device, joint, False)
        d = reply.params
        self.return_level[device] = d[MX28["status_return_level"].address]
        return_delays(self.bus.link, {device: d[MX28["return_delay_time"].address]})
        def byte(name: str) -> int:
            return d[MX28[name].address]

        def word(name: str) -> int:
            return _u16(d, MX28[name].address)

        return ServoState(
            device, joint, True, word("model_number"), byte("firmware_version"), byte("status_return_level"),
            byte("temperature_limit"), byte("alarm_shutdown"), byte("torque_enable") == 1, byte("p_gain"),
            angle_of(word("goal_position"), self.spec), word("moving_speed"), word("torque_limit"),
            angle_of(word("present_position"), self.spec),
            signed(word("present_speed")) * SPEED_RAD_S_PER_UNIT, signed(word("present_load")) / TORQUE_LIMIT_FULL,
            byte("present_voltage") * VOLTS_PER_UNIT, byte("present_temperature"), reply.errors,
            byte("return_delay_time"))

    def servos(self) -> list[ServoState]:
        """Every servo of the spec, in ID order."""
        return [self.servo(device) for device in self.ids]

    def replies_to_writes(self, device: int) -> bool:
        """Whether ``device`` answers writes (status return level 2, the default; learnt from :meth:`servo`)."""
        return self.return_level.get(device, 2) >= 2

    def write_each(self, register: str, values: dict[int, int]) -> list[int]:
        """Write ``register`` of each servo {id: value}, confirmed where the servo answers writes; the IDs that did
        not confirm (no reply, or one saying the write arrived damaged: the firmware does not execute it)."""
        r = MX28[register]
        failed = []
        for device, value in values.items():
            reply = self.bus.write(device, r.address, value.to_bytes(r.size, "little"),
                                   reply=self.replies_to_writes(device))
            if self.replies_to_writes(device) and (reply is None or reply.code & DAMAGED):
                failed.append(device)
        return failed

    def sync(self, register: str, values: dict[int, int]) -> None:
        """Write ``register`` of several servos in one SYNC_WRITE (no reply)."""
        r = MX28[register]
        self.bus.sync_write(r.address, r.size, {d: v.to_bytes(r.size, "little") for d, v in values.items()})

    def positions(self, devices: Sequence[int] | None = None) -> dict[int, float]:
        """Present positions [rad] of the servos that answer."""
        out = {}
        for device in devices or self.ids:
            reply = self.bus.read(device, MX28["present_position"].address, 2)
            if reply is not None:
                out[device] = angle_of(_u16(reply.params, 0), self.spec)
        return out

    def take_control(self, positions: dict[int, float], p_gains: dict[int, int] | None = None) -> list[int]:
        """Torque on without a jump: goals where the joints are (``positions`` {id: rad}), P gains (default the
        framework's), moving speed 0 (the servo's own speed profile off: the 8 ms goals set the pace), torque limit
        at its full value, then torque enable; the IDs that did not confirm."""
        ticks = {d: int(servo_to_ticks(np.array([q]), self.spec)[0]) for d, q in positions.items()}
        gains = {d: (p_gains or {}).get(d, DEFAULT_P_GAIN) for d in ticks}
        self.sync("goal_position", ticks)
        self.sync("p_gain", gains)
        self.sync("moving_speed", {d: 0 for d in ticks})
        self.sync("torque_limit", {d: TORQUE_LIMIT_FULL for d in ticks})
        return self.write_each("torque_enable", {d: 1 for d in ticks})

    def torque(self, on: bool, devices: Sequence[int] | None = None) -> list[int]:
        """Torque on or off; the IDs that did not confirm."""
        return self.write_each("torque_enable", {d: int(on) for d in devices or self.ids})

    def torque_limit(self, value: int, devices: Sequence[int] | None = None) -> None:
        """Every servo's torque limit (0..1023) in one SYNC_WRITE."""
        self.sync("torque_limit", {d: int(min(max(value, 0), TORQUE_LIMIT_FULL)) for d in devices or self.ids})

