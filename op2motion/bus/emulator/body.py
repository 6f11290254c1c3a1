"""The emulated OP2's body: a physics :class:`~op2motion.physics.Engine` (the floor and the robot, 1 kHz) driven by
the MX-28 servo model (:class:`~op2motion.model.servo.ServoModel`) from the servos' registers, and the registers
filled from the simulated body, all twenty servos at once (their tables side by side: :mod:`.bank`).

Per servo, from its table: torque enable (off: no active torque), the P gain (the model's stiffness per P), the goal
position, the moving speed (non-zero: the servo moves its set point towards the goal at that speed), the torque
limit (the active torque clipped at that share of the model's most torque, and scaled by the supply against the
rated voltage). Back to the tables: present position, speed and load, voltage, temperature (a first-order thermal
model: :data:`RISE_AT_STALL_C` above :data:`AMBIENT_C` at sustained stall torque, time constant
:data:`THERMAL_TAU_S`), moving; and the board's gyro and accelerometer (:class:`~op2motion.physics.sensors.Imu`,
sampled every 8 ms of simulated time) through the spec's IMU mapping
(:func:`~op2motion.robot.imu.encode_imu`), its supply voltage. A servo held at its torque limit for
:data:`OVERLOAD_S` latches the overload error.

Starts (:data:`STARTS`): ``standing`` (the book's standing pose on both feet, torque on), ``lying_front`` (face
down), ``lying_back`` (face up), ``lying_left`` and ``lying_right`` (on that side; the physics check's lying
placements, :func:`op2motion.physics.body.lying_placement`), placed by ``engine.reset`` and settled before the first
byte is served.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np

from op2motion.bus.emulator.bank import ServoTables
from op2motion.bus.emulator.devices import Board, EmulatedServo
from op2motion.bus.tables import SPEED_RAD_S_PER_UNIT, TORQUE_LIMIT_FULL, magnitudes
from op2motion.robot.imu import encode_imu, imu_of
from op2motion.robot.spec import Spec

if TYPE_CHECKING:
    from op2motion.physics import EngineName

class Drive(NamedTuple):
    """What the servos' registers ask of the motors (20,) each: torque enabled, goal [rad], moving speed [rad/s]
    (0: as fast as it can), stiffness [N·m/rad], torque limit [N·m]; and what follows from them for every physics
    step until a register changes: ``free`` (no moving speed: the set point jumps to the goal), ``all_free``,
    ``all_enabled``, the set point's largest move a step either way [rad], the torque at which a servo counts as at
    its limit [N·m] (infinite for one that cannot be: torque off, or a limit of 0), and ``limited``: some servo's
    torque limit is below the model's most torque (else clipping at the model's most torque is all the clipping)."""

    enabled: np.ndarray
    goal: np.ndarray
    speed: np.ndarray
    kp: np.ndarray
    limit: np.ndarray
    free: np.ndarray
    all_free: bool
    all_enabled: bool
    step_low_rad: np.ndarray
    step_high_rad: np.ndarray
    at_limit_nm: np.ndarray
    limited: bool


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
        self._tick_offset = spec.servo.center_tick + self.horn_ticks   # a joint at 0 reads this [tick]
        self._drive_keys: tuple[bytes, bool, bytes] = (b"", False, b"")   # the goals', the power, the other registers'
        self._drive: Drive | None = None
        self._imu_unsent = True             # the gyro and accelerometer read since the board's words were written
        self._saturating = False            # some servo's time at its limit is above 0
        self._place()

    def _place(self) -> None:
        """Put the robot where its start says, servos holding the start pose, and let it settle."""
        from op2motion.physics.body import Body, lying_placement, placement

        if self.start == "standing":
            placed = placement(Body(self.spec), self.pose, "double")
            pos, rot = placed.pos, placed.rot
        else:
            pos, rot = lying_placement(Body(self.spec), self.pose, self.start.removeprefix("lying_"))
        self.engine.reset(pos, rot, self.pose)
        self.engine.set_gravity(1.0)
        kp = self.model.kp_of(np.full(len(self.pose), self.spec.servo.p_gain_default))
        for _ in range(int(round(SETTLE_S / self.dt))):
            q, _ = self.engine.state()
            self.engine.step(self.model.active_torque(self.pose, q, kp))
        self.gyro, self.accel, _ = self.sensor.read(self.engine, self.engine.state()[0], 1.0)

    def drive(self, tables: ServoTables, powered: bool) -> Drive:
        """What the servos' registers (``tables``) ask of the motors now (good until a register is written): torque
        enabled, goal [rad], moving speed [rad/s], stiffness, torque limit [N·m], and what follows (:class:`Drive`).
        Worked out again only as far as those registers or the power changed."""
        goals, others = tables.drive_keys()
        drive = self._drive
        if drive is None or (powered, others) != self._drive_keys[1:]:
            drive = self._new_drive(tables, powered)
        elif goals != self._drive_keys[0]:
            drive = drive._replace(goal=self._goal_rad(tables))
        self._drive, self._drive_keys = drive, (goals, powered, others)
        return drive

    def _goal_rad(self, tables: ServoTables) -> np.ndarray:
        """The goal positions [rad] (read-only: the set point may be this very array)."""
        goal = tables.column("goal_position").astype(float)
        goal = (goal - self.horn_ticks - self.spec.servo.center_tick) * self.spec.servo.rad_per_tick
        goal.flags.writeable = False
        return goal

    def _new_drive(self, tables: ServoTables, powered: bool) -> Drive:
        enabled = (tables.column("torque_enable") == 1) & powered
        speed = tables.column("moving_speed").astype(float) * SPEED_RAD_S_PER_UNIT
        kp = self.model.kp_of(tables.column("p_gain").astype(float))
        share = tables.column("torque_limit").astype(float) / TORQUE_LIMIT_FULL
        volts = min(1.0, self.supply_v / self.rated_v)
        limit = self.model.torque_max * share * volts * enabled
        free = speed <= 0.0
        at_limit = np.where(enabled & (limit > 0), OVERLOAD_SHARE * np.maximum(limit, 1e-9), np.inf)
        return Drive(enabled, self._goal_rad(tables), speed, kp, limit, free, bool(free.all()), bool(enabled.all()),
                     -speed * self.dt, speed * self.dt, at_limit, bool((limit < self.model.torque_max).any()))

    def step(self, n: int, servos: Sequence[EmulatedServo], drive: Drive) -> None:
        """``n`` physics steps as ``drive`` (:meth:`drive`) asks; a servo held at its limit latches its overload.
        The torque is the servo model's within the torque limit (the limit is at most the model's most torque)."""
        state, engine_step, active_torque = self.engine.state, self.engine.step, self.model.active_torque
        kp, at_limit_nm = drive.kp, drive.at_limit_nm
        limit = drive.limit if drive.limited else None    # None: every limit is the most torque, where the model clips
        for _ in range(n):
            q, _ = state()
            self.command = self._set_point(drive, q)
            self.torque = torque = active_torque(self.command, q, kp, limit)
            engine_step(torque, np.array([self.push_n, 0.0, 0.0]) if self.push_n else None)
            at_limit = np.abs(torque) >= at_limit_nm
            held = np.count_nonzero(at_limit)
            if held or self._saturating:                # else every servo's time at its limit stays 0
                self.saturated_s = np.where(at_limit, self.saturated_s + self.dt, 0.0)
                self._saturating = bool(held)
            self.steps += 1
            if self.steps % 8 == 0:
                self.gyro, self.accel, _ = self.sensor.read(self.engine, q, 1.0)
                self._imu_unsent = True
        heat = RISE_AT_STALL_C * (self.torque / self.model.stall_torque) ** 2
        self.temperature += (AMBIENT_C + heat - self.temperature) * (n * self.dt / THERMAL_TAU_S)
        if self._saturating and np.count_nonzero(self.saturated_s >= OVERLOAD_S):
            for i in np.flatnonzero(self.saturated_s >= OVERLOAD_S).tolist():
                servos[i].overloaded = True

    def _set_point(self, drive: Drive, q: np.ndarray) -> np.ndarray:
        """Where each servo drives its joint this step [rad]: its goal, or towards it at its moving speed; a limp
        servo's set point follows its joint ``q``."""
        if drive.all_free:
            command = drive.goal                                        # read-only: shared, never changed in place
        else:
            move = np.minimum(np.maximum(drive.goal - self.command, drive.step_low_rad), drive.step_high_rad)
            command = np.where(drive.free, drive.goal, self.command + move)
        return command if drive.all_enabled else np.where(drive.enabled, command, q)

    def sense(self, servos: Sequence[EmulatedServo], tables: ServoTables, board: Board,
              overrides: dict[int, float]) -> None:
        """The present-state registers (``tables``, the servos' rows) and the board's IMU and voltage from the body
        (``overrides``: forced temperatures {id: °C}); a servo whose alarm shutdown a condition trips drops its
        torque."""
        q, dq = self.engine.state()
        s = self.spec.servo
        ticks = np.minimum(np.maximum(np.rint(q / s.rad_per_tick).astype(int) + self._tick_offset, s.min_tick),
                           s.max_tick)
        n = len(q)
        both = magnitudes(np.concatenate((dq / SPEED_RAD_S_PER_UNIT,
                                          self.torque / self.model.torque_max * TORQUE_LIMIT_FULL)))
        moving = (np.abs(self.command - q) > MOVING_RAD) | (np.abs(dq) > MOVING_RAD_S)
        celsius = self.temperature.tolist()
        temperature = self.temperature
        if overrides:
            celsius = [overrides.get(servo.id, c) for servo, c in zip(servos, celsius)]
            temperature = np.array(celsius)
        for servo, c in zip(servos, celsius):
            servo.temperature_c, servo.voltage_v = c, self.supply_v
        volts = int(round(self.supply_v * 10))
        tables.put_present(ticks, both[:n], both[n:], volts, np.minimum(np.maximum(np.rint(temperature), 0), 255),
                           moving)
        overloaded = [servo.overloaded for servo in servos]
        tables.enforce_alarms(volts, temperature, any(overloaded) and np.array(overloaded))
        if self._imu_unsent:                           # the board's IMU words change when the IMU is read
            for register, count in encode_imu(self.imu, self.gyro, self.accel).items():
                board.table[register:register + 2] = count.to_bytes(2, "little")
            self._imu_unsent = False
        board.set("voltage", volts)

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
