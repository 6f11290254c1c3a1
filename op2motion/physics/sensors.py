"""What the robot's controller sees: the CM-730's gyro and accelerometer and the servos' positions, as simulated.

The gyro reads the torso's angular velocity [rad/s] and the accelerometer its specific force [m/s²] (the
acceleration less gravity: +9.81 m/s² along the torso's z when it stands still and upright), both in the torso frame
(x forward, y left, z up); the acceleration is the torso origin's velocity change over the last control period. A
real robot reads them, and the joint positions, some milliseconds before its goals take effect, with noise:
:class:`Sensors` sets the latency (whole control periods) and the noise (normal, seeded) of a run.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from op2motion.errors import InputError
from op2motion.physics.engine import Engine
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import GRAVITY_M_S2

MAX_LATENCY_S = 0.1


@dataclass(frozen=True)
class Sensors:
    """Latency [s] of every reading (rounded to whole control periods), the standard deviations of the gyro's
    [rad/s], the accelerometer's [m/s²] and the joint positions' [rad] noise, and the noise's seed."""

    latency_s: float = 0.0
    gyro_noise_rad_s: float = 0.0
    accel_noise_m_s2: float = 0.0
    joint_noise_rad: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.latency_s) and 0.0 <= self.latency_s <= MAX_LATENCY_S):
            raise InputError(f"expected 0 to {MAX_LATENCY_S:g} s, got {self.latency_s!r}", "latency_s")
        for name in ("gyro_noise_rad_s", "accel_noise_m_s2", "joint_noise_rad"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise InputError(f"expected a standard deviation >= 0, got {value!r}", name)

    @property
    def delay_ticks(self) -> int:
        """The latency in control periods."""
        return int(round(self.latency_s / CONTROL_PERIOD_S))


Reading = tuple[np.ndarray, np.ndarray, np.ndarray]      # gyro (3,), accelerometer (3,), joint positions (20,)


class Imu:
    """The readings of one run: measured every control tick, handed out :attr:`Sensors.delay_ticks` later."""

    def __init__(self, sensors: Sensors = Sensors()):
        self.sensors = sensors
        self.rng = np.random.default_rng(sensors.seed)
        self.last_velocity: np.ndarray | None = None
        self.queue: deque[Reading] = deque()

    def _measure(self, engine: Engine, q: np.ndarray, gravity_scale: float) -> Reading:
        _, rot = engine.base()
        linear, angular = engine.base_velocity()
        accel = np.zeros(3) if self.last_velocity is None else (linear - self.last_velocity) / CONTROL_PERIOD_S
        self.last_velocity = linear
        gyro = rot.T @ angular
        specific = rot.T @ (accel + np.array([0.0, 0.0, GRAVITY_M_S2 * gravity_scale]))
        s = self.sensors
        if s.gyro_noise_rad_s or s.accel_noise_m_s2 or s.joint_noise_rad:
            gyro = gyro + self.rng.normal(0.0, s.gyro_noise_rad_s, 3)
            specific = specific + self.rng.normal(0.0, s.accel_noise_m_s2, 3)
            q = q + self.rng.normal(0.0, s.joint_noise_rad, q.shape)
        return gyro, specific, q

    def read(self, engine: Engine, q: np.ndarray, gravity_scale: float) -> Reading:
        """This tick's measurement goes in; the one from :attr:`Sensors.delay_ticks` ticks ago comes out (the oldest
        one while the run is younger than the latency)."""
        self.queue.append(self._measure(engine, q, gravity_scale))
        while len(self.queue) > self.sensors.delay_ticks + 1:
            self.queue.popleft()
        return self.queue[0]
