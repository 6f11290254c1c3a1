"""How is the robot lying? From its accelerometer: which side is down, and how far from upright.

At rest the accelerometer reads the specific force, +g along the world's up direction, in the torso frame (x
forward, y left, z up). Lying face down the torso's front points at the floor, so up is the torso's -x; face up, +x;
on its left side, -y; on its right side, +y; upright, +z. :func:`lying_side` names the axis nearest to up.

That the robot is down is decided as on the robot (:mod:`op2motion.robot.imu`, one home for both): the torso more
than :data:`FALL_TILT_DEG` from upright, or the ROBOTIS framework's own test on the CM-730's fore-aft accelerometer
counts (:class:`~op2motion.robot.imu.FallWatch`, the spec's ``[imu]`` mapping: FALLEN_F/B_LIMIT over 30 readings).
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.robot.imu import FALL_TILT_RAD, attitude

FALL_TILT_DEG = math.degrees(FALL_TILT_RAD)     # the torso this far from upright: down
UPRIGHT_TILT_DEG = 25.0       # within this of upright: standing again
SIDES = ("front", "back", "left", "right")


def tilt_deg(accel_m_s2: np.ndarray) -> float:
    """The torso's tilt from upright [deg] that a still accelerometer reading (3,) [m/s²] shows."""
    return math.degrees(attitude(np.asarray(accel_m_s2, dtype=float))[2])


def lying_side(accel_m_s2: np.ndarray) -> str:
    """``front`` (face down), ``back`` (face up), ``left``, ``right`` or ``upright`` (and ``head`` for a robot on
    its head): the torso axis nearest to the up direction of a still accelerometer reading (3,) [m/s²]."""
    a = np.asarray(accel_m_s2, dtype=float)
    i = int(np.argmax(np.abs(a)))
    return (("front", "back"), ("left", "right"), ("head", "upright"))[i][int(a[i] > 0.0)]
