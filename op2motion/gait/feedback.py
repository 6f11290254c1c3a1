"""The walk controller's gains (:class:`Feedback`, SI units) and the stock gait's gyro gains they start from."""

from __future__ import annotations

import math
from dataclasses import dataclass

from op2motion.errors import InputError

#: The stock gait's gyro balance gains in SI [s] (rad of joint per rad/s of torso rate): hip roll and ankle roll
#: from the roll rate, knee and ankle pitch from the pitch rate. Walking.cpp's 0.5, 0.3, 0.9, 1.0 ticks per gyro
#: count times 4 (the 4096-tick build), with 1 tick = 0.088° and 1 count = 3.125 °/s.
STOCK_GYRO_GAINS_S = (0.056, 0.034, 0.101, 0.113)
#: The gyro gains the controller uses: 0.6 of the stock ones. With 16 ms of sensor latency the stock gains make
#: servos 1.6 times stiffer than the model oscillate (PyBullet and MuJoCo alike); the swing leg's learnt
#: feed-forward (:mod:`.learning`) gives soft servos back what the lower damping takes from them.
GYRO_GAINS_S = (0.0336, 0.0204, 0.0606, 0.0678)
#: How much the gyro gains grow for soft servos: by this share at full measured softness (:mod:`.calibration`), so
#: 0.6 of the stock gains at the model's stiffness become the full stock gains at 0.6 of it. Soft servos turning in
#: place fell to a 2 N push from the side with 0.6 of the stock gains and stand it with the stock gains.
SOFT_GYRO = 1.0 / 0.6 - 1.0


@dataclass(frozen=True)
class Feedback:
    """The stabiliser's gains (SI).

    Attributes:
        kp, ki, kd: attitude error [rad] -> body turn [rad] (``kp``), its integral [rad·s] (``ki`` [1/s]), the gyro
            [rad/s] (``kd`` [s]), per axis (pitch, roll).
        attitude_tau_s: the attitude filter's time constant [s].
        gyro: joint damping [s] (rad per rad/s): hip roll, knee, ankle pitch, ankle roll.
        heading, heading_ki: the swing foot's steer per rad of heading error [1] and of its integral [1/s].
        cross_track: heading error [rad] per metre of sideways error from the planned line.
        joint_ki: the legs' sag trims [1/s].
        learn_gain, learn_shift_rows: the swing leg's learnt feed-forward: share of a miss kept per step, and rows
            from a goal to the measurement it shows in.
        latency_s: how late the joint readings arrive [s] (whole control periods).
        soft_kp: attitude error [rad] -> body turn [rad] added to ``kp`` in proportion to the servos' measured
            softness (:mod:`.calibration`: all of it at 0.6 of the model's stiffness or softer, none at the model's).
        calibrate: measure the servos' stiffness while standing and add the feed-forward softer servos lack.
        accel_tau_s: the accelerometer's low-pass [s] (as a vector) before its tilt is taken; 0: each raw sample.
        soft_gyro: share the gyro gains grow by at full measured softness (:data:`SOFT_GYRO`).
        placement: share of the feet's placement error across the direction of travel (leg odometry,
            :mod:`.odometry`) the next swing foot is moved against.
        accept_landing: after the closing step, hold the landed foot where it landed (no pull into the planned
            stance).
    """

    kp: tuple[float, float] = (0.0, 0.0)
    ki: tuple[float, float] = (0.0, 0.0)
    kd: tuple[float, float] = (0.0, 0.0)
    attitude_tau_s: float = 0.5
    gyro: tuple[float, float, float, float] = GYRO_GAINS_S
    heading: float = 0.3
    heading_ki: float = 0.3
    cross_track: float = 1.5
    joint_ki: float = 0.7
    learn_gain: float = 0.3
    learn_shift_rows: int = 3
    latency_s: float = 0.016
    soft_kp: tuple[float, float] = (0.6, 0.0)
    calibrate: bool = True
    accel_tau_s: float = 0.1
    placement: float = 0.5
    soft_gyro: float = SOFT_GYRO
    accept_landing: bool = True

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd", "soft_kp"):
            values = getattr(self, name)
            if len(values) != 2 or not all(math.isfinite(v) and 0.0 <= v <= 100.0 for v in values):
                raise InputError(f"expected two gains (pitch, roll) from 0 to 100, got {values!r}", name)
        if len(self.gyro) != 4 or not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in self.gyro):
            raise InputError(f"expected four gyro gains (hip roll, knee, ankle pitch, ankle roll) from 0 to 1 s, got "
                             f"{self.gyro!r}", "gyro")
        if not (isinstance(self.learn_shift_rows, int) and 0 <= self.learn_shift_rows <= 25):
            raise InputError(f"expected 0 to 25 rows, got {self.learn_shift_rows!r}", "learn_shift_rows")
        for name in ("calibrate", "accept_landing"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(f"expected true or false, got {getattr(self, name)!r}", name)
        for name, (low, high, what) in _RANGES.items():
            value = getattr(self, name)
            if not (math.isfinite(value) and low <= value <= high):
                raise InputError(f"expected {what} from {low:g} to {high:g}, got {value!r}", name)


#: The scalar gains' ranges: (lowest, highest, what it is).
_RANGES = {"attitude_tau_s": (0.01, 10.0, "a time [s]"), "accel_tau_s": (0.0, 1.0, "a time [s]"),
           "latency_s": (0.0, 0.1, "a time [s]"), "learn_gain": (0.0, 1.0, "a share"),
           "placement": (0.0, 1.0, "a share"), "soft_gyro": (0.0, 10.0, "a share"),
           "heading": (0.0, 100.0, "a gain"), "heading_ki": (0.0, 100.0, "a gain"),
           "cross_track": (0.0, 100.0, "a gain"), "joint_ki": (0.0, 100.0, "a gain")}

OPEN_LOOP = Feedback(ki=(0.0, 0.0), gyro=(0.0, 0.0, 0.0, 0.0), heading=0.0, heading_ki=0.0, cross_track=0.0,
                     joint_ki=0.0, learn_gain=0.0, soft_kp=(0.0, 0.0), calibrate=False, placement=0.0,
                     accept_landing=False)
