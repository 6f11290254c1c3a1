"""The stock ROBOTIS Walking module as a physics :class:`~op2motion.physics.Controller`: the emulated module
(:mod:`.stock_walking`) plays a walk of ``steps`` steps, its gyro balance reading the torso's gyro as the framework
reads the CM-730 (the spec's ``[imu]`` mapping: the counts from the centre of the fore-aft and the sideways channels).

The walk runs as the framework's demos run it: the robot stands in the module's own stance while gravity ramps in and
settles (:data:`~op2motion.physics.RAMP_S` + :data:`~op2motion.gait.measures.WALK_SETTLE_S`), then ``Start()`` with the
commanded step (``X/Y/A_MOVE_AMPLITUDE``); ``Stop()`` as the last step begins, after which the module closes the
walk itself (the step is latched to zero at its next phase) and halts; the last goals are held
:data:`~op2motion.gait.measures.WALK_HOLD_S`.

The plan the judge compares the run with (:func:`stock_plan`) is the same schedule played open loop (balance off),
its torso path worked out from the legs' forward kinematics on the spec's robot with the standing foot flat where it
landed (the stock gait plans no torso path: this is where its own foot placements put the torso); a foot counts as
lifted once its planned sole is :data:`~op2motion.robot.support.LIFTED_M` above the floor (the stock swing starts
and ends on the floor); the steady window runs from the second step's touchdown to the last full step's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from op2motion.gait.measures import WALK_HOLD_S, WALK_SETTLE_S, walk_measures
from op2motion.gait.stock_config import StockConfig
from op2motion.gait.stock_walking import ARM_POSE_DEG, StockTick, StockWalking, angle_to_tick
from op2motion.kinematics.leg_ik import leg_fk, leg_of
from op2motion.physics import RAMP_S, Plan, WalkClock
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.imu import encode_imu, imu_of
from op2motion.robot.joints import ticks_to_servo
from op2motion.robot.spec import Spec
from op2motion.robot.support import LIFTED_M, SIDES, Support

HEAD_P_GAIN = 32                       # the framework's default gain (the Head module's joints)
MAX_STEPS = 200
CLOSE_S = 3.0                          # after Stop() the module halts within two half periods; this is ample [s]


@dataclass(frozen=True)
class StockCommand:
    """The step the stock module is told to walk: forward and sideways [mm], turn [deg] per step."""

    x_mm: float
    y_mm: float = 0.0
    a_deg: float = 0.0


@dataclass(frozen=True)
class _Schedule:
    """The open-loop rows of a stock walk: goals (K, 20) [rad] and P gains (K, 20), the foot swinging at each row
    (None in double support), when Start() comes (row), the row each swing started, and the row the module halted."""

    goals: np.ndarray
    p_gains: np.ndarray
    swinging: tuple[str | None, ...]
    start_row: int
    swing_rows: tuple[int, ...]
    halt_row: int


class _Player:
    """The module driven by the demos' schedule (Start at ``start_row``, Stop as the ``steps``-th swing begins)."""

    def __init__(self, config: StockConfig, spec: Spec, steps: int, command: StockCommand):
        self.walk = StockWalking(config, spec)
        self.steps, self.command = steps, command
        self.spec = spec
        self.start_row = int(round((RAMP_S + WALK_SETTLE_S) / CONTROL_PERIOD_S))
        self.row = 0
        self.swings: list[int] = []
        self.previous: str | None = None
        self.halt_row: int | None = None
        base = {name: angle_to_tick(deg) for name, deg in ARM_POSE_DEG.items()}
        self.ticks = np.full(len(spec.joint_names), spec.servo.center_tick, dtype=float)
        for name, tick in base.items():
            self.ticks[spec.joint_names.index(name)] = tick
        self.gains = np.full(len(spec.joint_names), float(HEAD_P_GAIN))
        for name in ARM_POSE_DEG:
            self.gains[spec.joint_names.index(name)] = 8.0

    def tick(self, rl_gyro: float = 0.0, fb_gyro: float = 0.0) -> StockTick:
        if self.row == self.start_row:
            self.walk.command(self.command.x_mm, self.command.y_mm, self.command.a_deg)
            self.walk.start()
        out = self.walk.tick(rl_gyro, fb_gyro)
        if out.swinging is not None and out.swinging != self.previous and self.row > self.start_row:
            self.swings.append(self.row)
            if len(self.swings) == self.steps:
                self.walk.stop()
        self.previous = out.swinging
        if self.halt_row is None and self.row > self.start_row and not self.walk.real_running:
            self.halt_row = self.row
        for name, tick in out.ticks.items():
            k = self.spec.joint_names.index(name)
            self.ticks[k] = tick
            self.gains[k] = out.p_gains[name]
        self.row += 1
        return out


def _schedule(config: StockConfig, spec: Spec, steps: int, command: StockCommand) -> _Schedule:
    player = _Player(config, spec, steps, command)
    goals, gains, swinging = [], [], []
    limit = player.start_row + int(round((steps * config.period_time_ms / 2000.0 + CLOSE_S) / CONTROL_PERIOD_S))
    while player.row < limit and (player.halt_row is None or player.row <= player.halt_row):
        out = player.tick()
        goals.append(ticks_to_servo(player.ticks.copy(), spec))
        gains.append(player.gains.copy())
        swinging.append(out.swinging)
    halt = player.halt_row if player.halt_row is not None else len(goals) - 1
    return _Schedule(np.array(goals), np.array(gains), tuple(swinging), player.start_row, tuple(player.swings), halt)


def _flat(rot: np.ndarray) -> np.ndarray:
    """The rotation's heading alone (a foot set down flat)."""
    yaw = float(np.arctan2(rot[1, 0], rot[0, 0]))
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class PlannedTorso:
    """Where the rows' leg angles put the torso with the standing foot flat on the floor where it landed (the feet
    start flat, their midpoint at the origin): its positions (K, 3) [m] and rotations (K, 3, 3), and each sole's
    planned height above the floor (K,) [m] by side."""

    positions: np.ndarray
    rotations: np.ndarray
    sole_heights: dict[str, np.ndarray]


def planned_torso(goals: np.ndarray, swinging: tuple[str | None, ...], spec: Spec) -> PlannedTorso:
    """The torso the rows ``goals`` (K, 20) [rad] plan, ``swinging`` naming each row's swing foot (see
    :class:`PlannedTorso`)."""
    legs = {side: leg_of(spec, side) for side in SIDES}
    soles = {side: leg_fk(leg, goals[:, list(leg.index)]) for side, leg in legs.items()}   # in the torso frame
    rot0 = soles["left"][1][0].T                              # the torso over a flat left sole
    mid = 0.5 * (soles["left"][0][0] + soles["right"][0][0])
    world = {side: (rot0 @ (soles[side][0][0] - mid) * np.array([1.0, 1.0, 0.0]), _flat(rot0 @ soles[side][1][0]))
             for side in SIDES}
    anchor, previous = "left", None
    positions, rotations = [], []
    heights: dict[str, list[float]] = {side: [] for side in SIDES}
    for k, swing in enumerate(swinging):
        if swing is not None and swing == anchor:
            anchor = "right" if swing == "left" else "left"
        pos_w, rot_w = world[anchor]
        sole_pos, sole_rot = soles[anchor][0][k], soles[anchor][1][k]
        torso_rot = rot_w @ sole_rot.T
        torso_pos = pos_w - torso_rot @ sole_pos
        if previous is not None and swing is None:              # the swing foot landed: flat where it came down
            foot_pos = torso_pos + torso_rot @ soles[previous][0][k]
            world[previous] = (foot_pos * np.array([1.0, 1.0, 0.0]), _flat(torso_rot @ soles[previous][1][k]))
        positions.append(torso_pos)
        rotations.append(torso_rot)
        for side in SIDES:
            heights[side].append(float((torso_pos + torso_rot @ soles[side][0][k])[2]))
        previous = swing
    return PlannedTorso(np.array(positions), np.array(rotations), {side: np.array(h) for side, h in heights.items()})


def stock_plan(config: StockConfig, spec: Spec, steps: int, command: StockCommand) -> Plan:
    """The physics plan of a stock walk (see the module docstring)."""
    s = _schedule(config, spec, steps, command)
    torso = planned_torso(s.goals, s.swinging, spec)
    positions, rotations, heights = torso.positions, torso.rotations, torso.sole_heights
    supports = tuple(Support.DOUBLE if w is None or heights[w][k] <= LIFTED_M else
                     Support.of("right" if w == "left" else "left") for k, w in enumerate(s.swinging))
    base = (positions, rotations)
    dt = CONTROL_PERIOD_S
    start_s = s.start_row * dt
    touchdowns = [next((k for k in range(r, len(s.swinging)) if s.swinging[k] is None), r) for r in s.swing_rows]
    last = touchdowns[min(steps, len(touchdowns)) - 1] if touchdowns else s.halt_row   # the last full step's
    steady_from = (touchdowns[1] if len(touchdowns) > 1 else s.start_row) * dt - start_s
    steady_to = last * dt - start_s
    clock = WalkClock(start_s, (s.halt_row - s.start_row) * dt, steady_from, max(steady_to, steady_from + dt))
    return Plan("walk", s.goals, s.p_gains, supports, dt, 0.0, (len(s.goals) - 1) * dt + WALK_HOLD_S, base,
                supports, clock, measure=walk_measures)


class StockWalkController:
    """The stock Walking module in the loop (see the module docstring).

    Args:
        config: The ``[Walking Config]`` settings.
        spec: The robot (its IMU mapping and geometry).
        steps: Steps before ``Stop()`` (1 to :data:`MAX_STEPS`).
        command: The step to walk (default: the config's ``x_move_amplitude_mm`` forward).
        balance: The module's gyro balance (``BALANCE_ENABLE``; on in the C++ framework).
    """

    def __init__(self, config: StockConfig, spec: Spec, steps: int = 20, command: StockCommand | None = None,
                 balance: bool = True):
        from op2motion.errors import InputError

        if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= MAX_STEPS:
            raise InputError(f"expected 1 to {MAX_STEPS} steps, got {steps!r}", "steps")
        self.config, self.spec, self.steps, self.balance = config, spec, steps, balance
        self.command = command if command is not None else StockCommand(config.x_move_amplitude_mm)
        self.plan = stock_plan(config, spec, steps, self.command)
        self._imu = imu_of(spec)
        self._fb = next(c.register for c in self._imu.gyro if c.axis == 1)     # the framework's FB_GYRO channel
        self._rl = next(c.register for c in self._imu.gyro if c.axis == 0)     # ... and RL_GYRO
        self._player = _Player(config, spec, steps, self.command)
        self._t = 0.0

    def _goals(self) -> dict[str, float]:
        return dict(zip(self.spec.joint_names, ticks_to_servo(self._player.ticks, self.spec).tolist()))

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The module's stance (its first tick)."""
        self._player = _Player(self.config, self.spec, self.steps, self.command)
        self._t = 0.0
        self._player.tick()
        return self._goals()

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """One 8 ms tick of the module, its balance fed the gyro's counts from the centre."""
        self._t = t_s
        rl = fb = 0.0
        if self.balance:
            words = encode_imu(self._imu, np.asarray(gyro_rad_s, dtype=float), np.asarray(accel_m_s2, dtype=float))
            rl, fb = words[self._rl] - self._imu.centre_count, words[self._fb] - self._imu.centre_count
        self._player.tick(rl, fb)
        return self._goals()

    @property
    def done(self) -> bool:
        """The module has halted and stood still for the plan's hold."""
        return self._t >= self.plan.end_s
