"""The sub-controller's gyro and accelerometer: register words <-> the torso frame, by the spec's ``[imu]`` mapping.

Each channel of :class:`~op2motion.robot.spec.ImuSpec` says which register measures what along which torso axis
(x forward, y left, z up), with which sign and scale, and why (``specs/op2.toml``); nothing about the board's
mounting is written here. :func:`decode_imu` gives the gyro [rad/s] and the accelerometer's specific force [m/s²] a
controller takes (:class:`~op2motion.physics.Controller`); :func:`encode_imu` is its inverse for the emulated board.
:func:`attitude` is the pitch and roll the gravity in a still accelerometer implies, and :class:`FallWatch` the
framework's own fall test (the fore-aft count averaged over 30 ticks beyond FALLEN_F_LIMIT / FALLEN_B_LIMIT).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Mapping, Sequence

import numpy as np

from op2motion.errors import SpecError
from op2motion.robot.spec import ImuChannel, ImuSpec, Spec

FALL_TILT_RAD = math.radians(45.0)  # the torso this far from upright is down (a walk's own tilt stays under 14°)
ARM_TILT_RAD = math.radians(20.0)   # a fall watch arms once the torso is this close to upright


def imu_of(spec: Spec) -> ImuSpec:
    """The spec's IMU mapping; a spec without an ``[imu]`` table cannot drive a robot."""
    if spec.imu is None:
        raise SpecError(f"{spec.path}: expected an [imu] table (the sub-controller's IMU mapping) to talk to a robot")
    return spec.imu


def registers(imu: ImuSpec) -> tuple[int, ...]:
    """Every IMU register (the low byte's address)."""
    return tuple(c.register for c in (*imu.gyro, *imu.accel))


def decode_imu(imu: ImuSpec, words: Mapping[int, int], centres: Mapping[int, float] | None = None
           ) -> tuple[np.ndarray, np.ndarray]:
    """Gyro (3,) [rad/s] and accelerometer (3,) [m/s²] in the torso frame from the board's words {register: count};
    ``centres`` {register: count} replaces the nominal centre where a channel was calibrated (:func:`gyro_centres`)."""
    centres = centres or {}

    def axis(channels: tuple[ImuChannel, ...]) -> np.ndarray:
        return np.array([c.sign * (words[c.register] - centres.get(c.register, imu.centre_count)) * c.scale
                         for c in channels])

    return axis(imu.gyro), axis(imu.accel)


def decode_span(imu: ImuSpec, data: bytes, start: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`decode_imu` from a block of the board's table read from address ``start``."""
    words = {r: data[r - start] | (data[r - start + 1] << 8) for r in registers(imu)}
    return decode_imu(imu, words)


GYRO_SAMPLES = 100                 # the framework's GYRO_WINDOW_SIZE: samples averaged for the gyro's centres
GYRO_STILL_SD = 2.0                # ... taken only if every channel's standard deviation is below this [counts]


def gyro_centres(imu: ImuSpec, samples: Sequence[Mapping[int, int]]) -> dict[int, float] | None:
    """The gyro's zero-rate counts {register: count} from ``samples`` of the board's words taken while the robot
    is still (the framework's calibration in ``MotionManager::Process``: the mean, if every channel's standard
    deviation is below :data:`GYRO_STILL_SD`); None if the robot moved (the nominal centre stays)."""
    if not samples:
        return None
    out = {}
    for c in imu.gyro:
        values = np.array([s[c.register] for s in samples], dtype=float)
        if values.std() >= GYRO_STILL_SD:
            return None
        out[c.register] = float(values.mean())
    return out


def encode_imu(imu: ImuSpec, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray) -> dict[int, int]:
    """The board's words {register: count} that read as ``gyro_rad_s`` and ``accel_m_s2`` (torso frame), rounded to
    the nearest count and held within 0..max (the sensors saturate)."""
    out = {}
    for channels, values in ((imu.gyro, gyro_rad_s), (imu.accel, accel_m_s2)):
        for c in channels:
            count = imu.centre_count + c.sign * float(values[c.axis]) / c.scale
            out[c.register] = int(min(max(round(count), 0), imu.max_count))
    return out


def attitude(accel_m_s2: np.ndarray) -> tuple[float, float, float]:
    """Pitch (leaning forward > 0), roll (about +x > 0) and tilt from upright [rad] that the gravity in a still
    accelerometer reading implies (the robot's own estimate; a moving robot's reading holds its acceleration too)."""
    ax, ay, az = (float(v) for v in accel_m_s2)
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    if norm == 0.0:
        return 0.0, 0.0, 0.0
    return math.atan2(-ax, az), math.atan2(ay, math.hypot(ax, az)), math.acos(max(-1.0, min(1.0, az / norm)))


def fore_aft_count(imu: ImuSpec, words: Mapping[int, int]) -> int:
    """The framework's FB_ACCEL: the raw count of the accelerometer channel along the torso's x axis."""
    return words[imu.accel[0].register]


def board_of(spec: Spec) -> ImuSpec:
    """The spec's IMU mapping, or the shipped OP2's when the spec states none (a simulated body's sensors still read
    as the robot's board would: the fall test in counts)."""
    if spec.imu is not None:
        return spec.imu
    from op2motion.robot.specfile import default_spec

    return imu_of(default_spec())


class FallWatch:
    """The framework's fall test: the fore-aft accelerometer count averaged over the spec's window; ``fallen`` is
    ``"front"`` (face down) below the front limit, ``"back"`` above the back limit, else None. A channel mounted
    with sign -1 flips the comparison, so the test is about the torso, not the board."""

    def __init__(self, imu: ImuSpec):
        self.imu = imu
        self.samples: deque[int] = deque(maxlen=imu.fallen_window)

    def add(self, words: Mapping[int, int]) -> str | None:
        """Add one tick's words; the verdict once the window is full."""
        self.samples.append(fore_aft_count(self.imu, words))
        if len(self.samples) < self.samples.maxlen:             # type: ignore[operator]
            return None
        mean = sum(self.samples) / len(self.samples)
        forward = self.imu.accel[0].sign * (mean - self.imu.centre_count)   # along +x, in counts
        front = self.imu.fallen_front_count - self.imu.centre_count          # negative
        back = self.imu.fallen_back_count - self.imu.centre_count            # positive
        return "front" if forward < front else "back" if forward > back else None
