"""The emulated OP2's body: a physics :class:`~op2motion.physics.Engine` (the floor and the robot, 1 kHz) driven by
the MX-28 servo model (:class:`~op2motion.model.servo.ServoModel`) from the servos' registers, and the registers
filled from the simulated body.

Per servo, from its table: torque enable (off: no active torque), the P gain (the model's stiffness per P), the goal
position, the moving speed (non-zero: the servo moves its set point towards the goal at that speed), the torque
limit (the active torque clipped at that share of the model's most torque, and scaled by the supply against the
rated voltage). Back to the tables: present position, speed and load, voltage, temperature (a first-order thermal
model: :data:`RISE_AT_STALL_C` above :data:`AMBIENT_C` at sustained stall torque, time constant
:data:`THERMAL_TAU_S`), moving; and the board's gyro and accelerometer (:class:`~op2motion.physics.sensors.Imu`,
sampled every 8 ms of simulated time) through the spec's IMU mapping (:func:`op2motion.robot.imu.encode`), its supply
voltage. A servo held at its torque limit for :data:`OVERLOAD_S` latches the overload error.

Starts (:data:`STARTS`): ``standing`` (the book's standing pose on both feet, torque on), ``lying_front`` (face
down), ``lying_back`` (face up), ``lying_left`` and ``lying_right`` (on that side; the physics check's lying
placements, :func:`op2motion.physics.body.lying_placement`), placed by ``engine.reset`` and settled before the first
byte is served.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np

from op2motion.bus.emulator.devices import Board, EmulatedServo
from op2motion.bus.tables import SPEED_RAD_S_PER_UNIT, TORQUE_LIMIT_FULL, magnitude
from op2motion.robot.imu import encode, imu_of
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.physics import EngineName

class Drive(NamedTuple):
    """What the servos' registers ask of the motors (20,) each: torque enabled, goal [rad], moving speed [rad/s]
    (0: as fast as it can), stiffness [N·m/rad], torque limit [N·m]."""

    enabled: np.ndarray
    goal: np.ndarray
    speed: np.ndarray
    kp: np.ndarray
    limit: np.ndarray


STARTS = ("standing", "lying_front", "lying_back", "lying_left", "lying_right")
AMBIENT_C = 30.0                   # the air inside the robot [°C]
START_TEMPERATURE_C = 36.0         # a servo's temperature when the emulator starts [°C]
RISE_AT_STALL_C = 60.0             # steady rise above ambient at sustained stall torque [°C]
THERMAL_TAU_S = 300.0              # the servo's thermal time constant [s]
OVERLOAD_S = 2.0                   # at the torque limit this long: the overload error latches
OVERLOAD_SHARE = 0.98              # "at the limit"
SETTLE_S = 1.5                     # simulated before serving, so the robot rests where it starts
MOVING_RAD = math.radians(0.5)     # a set point this far from the joint counts as moving
MOVING_RAD_S = 0.05                # ... and so does a joint this fast


class EmulatedBody:
    """The simulated OP2 behind the tables (see the module docstring)."""

    def __init__(self, spec: Spec, engine: EngineName, start: str, supply_v: float,
                 horn: dict[int, int] | None = None):
        from op2motion.model.servo import ServoModel
        from op2motion.physics.engine import make_engine
        from op2motion.physics.sensors import Imu
        from op2motion.robot.joints import BookAngles, book_to_servo

        if start not in STARTS:
            raise ValueError(f"expected one of {', '.join(STARTS)}, got {start!r}")
        self.spec, self.start = spec, start
        self.imu = imu_of(spec)
        self.model = ServoModel.of(spec)
        self.engine = make_engine(engine, spec, self.model)
        self.sensor = Imu()
        self.supply_v = supply_v
        self.rated_v = spec.servo.supply_voltage_v
        self.dt = self.engine.time_step
        self.pose = book_to_servo(BookAngles.standing("left"), spec)[0]
        n = len(spec.joints)
        self.horn_ticks = np.zeros(n, dtype=int)       # a horn mounted off: the reading less the joint [ticks]
        for device, ticks in (horn or {}).items():
            self.horn_ticks[device - 1] = ticks
        self.command = self.pose.copy()
        self.saturated_s = np.zeros(n)
        self.temperature = np.full(n, START_TEMPERATURE_C)
        self.torque = np.zeros(n)
        self.steps = 0
        self.gyro, self.accel = np.zeros(3), np.array([0.0, 0.0, 9.81])
        self.push_n = 0.0                   # a push forward (+x, world) at the torso's centre of mass [N]
        self._place()

    def _place(self) -> None:
        """Put the robot where its start says, servos holding the start pose, and let it settle."""
        from op2motion.physics.body import Body, lying_placement, placement

        if self.start == "standing":
            pos, rot, _, _ = placement(Body(self.spec), self.pose, "double")
        else:
            pos, rot = lying_placement(Body(self.spec), self.pose, self.start.removeprefix("lying_"))
        self.engine.reset(pos, rot, self.pose)
        self.engine.set_gravity(1.0)
        kp = self.model.kp_of(np.full(len(self.pose), self.spec.servo.p_gain_default))
        for _ in range(int(round(SETTLE_S / self.dt))):
            q, _ = self.engine.state()
            self.engine.step(self.model.active_torque(self.pose, q, kp))
        self.gyro, self.accel, _ = self.sensor.read(self.engine, self.engine.state()[0], 1.0)

    def drive(self, servos: Sequence[EmulatedServo], powered: bool) -> Drive:
        """What the servos' registers ask of the motors now (good until a register is written): torque enabled, goal
        [rad], moving speed [rad/s], stiffness, torque limit [N·m]."""
        enabled = np.array([powered and s.get("torque_enable") == 1 for s in servos], dtype=bool)
        goal = np.array([s.u16("goal_position") for s in servos], dtype=float)
        goal = (goal - self.horn_ticks - self.spec.servo.center_tick) * self.spec.servo.rad_per_tick
        speed = np.array([s.u16("moving_speed") for s in servos], dtype=float) * SPEED_RAD_S_PER_UNIT
        kp = self.model.kp_of(np.array([s.get("p_gain") for s in servos], dtype=float))
        share = np.array([s.u16("torque_limit") for s in servos], dtype=float) / TORQUE_LIMIT_FULL
        volts = min(1.0, self.supply_v / self.rated_v)
        return Drive(enabled, goal, speed, kp, self.model.torque_max * share * volts * enabled)

    def step(self, n: int, servos: Sequence[EmulatedServo], drive: Drive) -> None:
        """``n`` physics steps as ``drive`` (:meth:`drive`) asks; a servo held at its limit latches its overload."""
        count = len(servos)
        enabled, goal, speed, kp, limit = drive
        for _ in range(n):
            q, _ = self.engine.state()
            free = speed <= 0.0
            self.command = np.where(free, goal, self.command + np.clip(goal - self.command, -speed * self.dt,
                                                                        speed * self.dt))
            self.command = np.where(enabled, self.command, q)             # a limp servo's set point follows it
            torque = self.model.active_torque(self.command, q, kp)
            torque = np.minimum(np.maximum(torque, -limit), limit)
            self.engine.step(torque, np.array([self.push_n, 0.0, 0.0]) if self.push_n else None)
            self.torque = torque
            at_limit = enabled & (np.abs(torque) >= OVERLOAD_SHARE * np.maximum(limit, 1e-9)) & (limit > 0)
            self.saturated_s = np.where(at_limit, self.saturated_s + self.dt, 0.0)
            self.steps += 1
            if self.steps % 8 == 0:
                self.gyro, self.accel, _ = self.sensor.read(self.engine, q, 1.0)
        heat = RISE_AT_STALL_C * (self.torque / self.model.stall_torque) ** 2
        self.temperature += (AMBIENT_C + heat - self.temperature) * (n * self.dt / THERMAL_TAU_S)
        for i in range(count):
            if self.saturated_s[i] >= OVERLOAD_S:
                servos[i].overloaded = True

    def sense(self, servos: Sequence[EmulatedServo], board: Board, overrides: dict[int, float]) -> None:
        """The present-state registers and the board's IMU and voltage from the body (``overrides``: forced
        temperatures {id: °C})."""
        q, dq = self.engine.state()
        s = self.spec.servo
        ticks = np.clip(np.rint(q / s.rad_per_tick).astype(int) + s.center_tick + self.horn_ticks, s.min_tick,
                        s.max_tick).tolist()
        speed = [magnitude(v) for v in (dq / SPEED_RAD_S_PER_UNIT).tolist()]
        load = [magnitude(v) for v in (self.torque / self.model.torque_max * TORQUE_LIMIT_FULL).tolist()]
        moving = ((np.abs(self.command - q) > MOVING_RAD) | (np.abs(dq) > MOVING_RAD_S)).tolist()
        volts = int(round(self.supply_v * 10))
        for i, servo in enumerate(servos):
            servo.temperature_c = overrides.get(servo.id, float(self.temperature[i]))
            servo.voltage_v = self.supply_v
            servo.present(ticks[i], speed[i], load[i], volts, int(min(max(round(servo.temperature_c), 0), 255)),
                          int(moving[i]))
            servo.enforce_alarms()
        for register, count in encode(self.imu, self.gyro, self.accel).items():
            board.table[register:register + 2] = count.to_bytes(2, "little")
        board.set("voltage", int(round(self.supply_v * 10)))

    def truth(self) -> dict[str, float]:
        """Where the simulated torso is: position [m], yaw and tilt from upright [rad], simulated time [s]."""
        pos, rot = self.engine.base()
        return {"t_s": self.steps * self.dt, "x_m": float(pos[0]), "y_m": float(pos[1]), "z_m": float(pos[2]),
                "yaw_rad": math.atan2(float(rot[1, 0]), float(rot[0, 0])),
                "tilt_rad": math.acos(max(-1.0, min(1.0, float(rot[2, 2]))))}

    def joint_angles(self) -> np.ndarray:
        """The simulated joint angles (20,) [rad]."""
        return self.engine.state()[0].copy()

    def close(self) -> None:
        """Release the engine."""
        self.engine.close()
