"""How is the robot lying? From its accelerometer: the thresholds of a fall, and which side is down.

At rest the accelerometer reads the specific force, +g along the world's up direction, in the torso frame (x
forward, y left, z up). Lying face down the torso's front points at the floor, so up is the torso's -x; face up, +x;
on its left side, -y; on its right side, +y; upright, +z. :func:`lying_side` names the axis nearest to up.

Two named tests say the robot is down:

* the tilt: the torso's z axis more than :data:`FALL_TILT_DEG` from the vertical (the walk's own tilt stays under
  14° across the robustness family, the walk check calls 10° past its plan a fall);
* the ROBOTIS framework's (``MotionManager::Process``, v1.6.0): the fore-aft accelerometer (the CM-730's ACCEL_Y
  register, the robot's x axis) averaged over :data:`FRAMEWORK_SAMPLES` readings below :data:`FALLEN_F_LIMIT` counts
  (face down) or above :data:`FALLEN_B_LIMIT` (face up), 10-bit counts about :data:`ACCEL_CENTRE`. A count is
  :data:`ACCEL_RANGE_G` g over 512 (op2motion's README; NUbots reads the register as ±4 g: kept as data), so the
  limits are -7.0 and +3.9 m/s² along x: tilted 46° forward or 23° back.
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.robot.spec import GRAVITY_M_S2

FALL_TILT_DEG = 45.0          # the torso this far from upright: down
UPRIGHT_TILT_DEG = 25.0       # within this of upright: standing again
ACCEL_CENTRE = 512            # the CM-730's accelerometer counts at zero (10 bit)
FALLEN_F_LIMIT = 390          # the framework: the fore-aft average below this: fallen forward (face down)
FALLEN_B_LIMIT = 580          # ... above this: fallen backward (face up)
FRAMEWORK_SAMPLES = 30        # ... averaged over this many readings (8 ms apart)
ACCEL_RANGE_G = 3.0           # one count is this many g over 512 (op2motion's README; NUbots: 4 g)
SIDES = ("front", "back", "left", "right")


def counts_to_m_s2(counts: float) -> float:
    """An accelerometer reading in counts as specific force [m/s²] (:data:`ACCEL_RANGE_G` over 512 counts)."""
    return (counts - ACCEL_CENTRE) * ACCEL_RANGE_G * GRAVITY_M_S2 / ACCEL_CENTRE


FALLEN_F_M_S2 = counts_to_m_s2(FALLEN_F_LIMIT)
FALLEN_B_M_S2 = counts_to_m_s2(FALLEN_B_LIMIT)


def tilt_deg(accel_m_s2: np.ndarray) -> float:
    """The torso's tilt from upright [deg] that a still accelerometer reading (3,) [m/s²] shows."""
    a = np.asarray(accel_m_s2, dtype=float)
    norm = float(np.linalg.norm(a))
    return 0.0 if norm == 0.0 else math.degrees(math.acos(max(-1.0, min(1.0, float(a[2]) / norm))))


def lying_side(accel_m_s2: np.ndarray) -> str:
    """``front`` (face down), ``back`` (face up), ``left``, ``right`` or ``upright`` (and ``head`` for a robot on
    its head): the torso axis nearest to the up direction of a still accelerometer reading (3,) [m/s²]."""
    a = np.asarray(accel_m_s2, dtype=float)
    i = int(np.argmax(np.abs(a)))
    return (("front", "back"), ("left", "right"), ("head", "upright"))[i][int(a[i] > 0.0)]


def framework_fallen(fore_aft_m_s2: list[float]) -> str | None:
    """The framework's test on the last :data:`FRAMEWORK_SAMPLES` fore-aft readings [m/s²]: ``front``, ``back`` or
    None."""
    if len(fore_aft_m_s2) < FRAMEWORK_SAMPLES:
        return None
    mean = sum(fore_aft_m_s2[-FRAMEWORK_SAMPLES:]) / FRAMEWORK_SAMPLES
    return "front" if mean < FALLEN_F_M_S2 else "back" if mean > FALLEN_B_M_S2 else None
