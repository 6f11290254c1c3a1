"""A walk that reacts: the ZMP preview plan played every 8 ms with stabilisation from the robot's IMU.

:class:`WalkController` is a :class:`~op2motion.physics.Controller`: the physics check drives it, and so can a
robot bridge or another simulator, with the torso's gyro [rad/s] and accelerometer [m/s²] (torso frame: x forward,
y left, z up; the accelerometer reads +9.81 m/s² on z when upright and still) and the joint positions every 8 ms.
Inside, per tick:

1. **the plan** (:func:`.schedule.gait_plan`): the goals of this row, the planned torso pose and soles;
2. **the attitude**: a complementary filter of the gyro (integrated) and the accelerometer's direction of gravity
   (time constant :attr:`Feedback.attitude_tau_s`) estimates the torso's pitch and roll;
3. **the error** against the plan's torso attitude, its integral, and the gyro (the plan's rate is small);
4. **the correction**: the whole body turned about the support point (the stance sole's centre, or between both
   soles on two feet) by ``-(Kp e + Ki ∫e + Kd w)`` in pitch and roll; the legs from the closed-form IK with the soles
   where the plan puts them, so the swing foot keeps its path and lands flat;
5. **the goals**: the plan's goals (servo feed-forward included) plus the legs' change.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from op2motion.errors import InputError
from op2motion.gait.generator import Gait
from op2motion.gait.leg_ik import Leg, leg_ik, leg_of, rot_x, rot_y, rot_z
from op2motion.gait.presets import load_preset
from op2motion.gait.schedule import gait_plan
from op2motion.physics import Plan, Schedule
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES, Support

REACH_SHARE = 0.999                # a corrected leg stretches at most to this share of its length
MAX_HEADING_RAD = 0.2             # the swing foot is steered at most this far per step (11°)
MAX_TRIM_RAD = 0.15                # a leg joint's integral trim stays within this [rad] (8.6°)
MAX_CORRECTION_RAD = 0.25          # the stabiliser turns the body at most this far (14°)
#: The stock gait's gyro balance gains in SI [s] (rad of joint per rad/s of torso rate): hip roll and ankle roll
#: from the roll rate, knee and ankle pitch from the pitch rate. Walking.cpp's 0.5, 0.3, 0.9, 1.0 ticks per gyro
#: count times 4 (the 4096-tick build), with 1 tick = 0.088° and 1 count = 3.125 °/s.
STOCK_GYRO_GAINS_S = (0.056, 0.034, 0.101, 0.113)


@dataclass(frozen=True)
class Feedback:
    """The stabiliser's gains (SI): attitude error [rad] -> body turn [rad] (``kp``), its integral [rad·s] (``ki``
    [1/s]), the gyro [rad/s] (``kd`` [s]), per axis (pitch, roll); the attitude filter's time constant [s]."""

    kp: tuple[float, float] = (0.0, 0.0)
    ki: tuple[float, float] = (0.5, 0.0)
    kd: tuple[float, float] = (0.0, 0.0)
    attitude_tau_s: float = 0.5
    gyro: tuple[float, float, float, float] = STOCK_GYRO_GAINS_S
    heading: float = 0.3
    joint_ki: float = 0.7

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "kd"):
            values = getattr(self, name)
            if len(values) != 2 or not all(math.isfinite(v) and 0.0 <= v <= 100.0 for v in values):
                raise InputError(f"expected two gains (pitch, roll) from 0 to 100, got {values!r}", name)
        if not (math.isfinite(self.attitude_tau_s) and 0.01 <= self.attitude_tau_s <= 10.0):
            raise InputError(f"expected 0.01 to 10 s, got {self.attitude_tau_s!r}", "attitude_tau_s")
        if len(self.gyro) != 4 or not all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in self.gyro):
            raise InputError(f"expected four gyro gains (hip roll, knee, ankle pitch, ankle roll) from 0 to 1 s, got "
                             f"{self.gyro!r}", "gyro")
        for name in ("heading", "joint_ki"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value <= 100.0):
                raise InputError(f"expected a gain from 0 to 100, got {value!r}", name)


OPEN_LOOP = Feedback(ki=(0.0, 0.0), gyro=(0.0, 0.0, 0.0, 0.0), heading=0.0, joint_ki=0.0)


def attitude_of(rot: np.ndarray) -> np.ndarray:
    """Pitch and roll [rad] of a torso rotation: the tilt of its z axis towards +x (pitch: leaning forward > 0) and
    towards -y (roll: turned about +X > 0)."""
    z = rot[:, 2]
    return np.array([math.atan2(z[0], z[2]), math.atan2(-z[1], math.hypot(z[0], z[2]))])


def _within_reach(leg: Leg, sole: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The sole target (3,) [m] pulled towards the hip along the hip–ankle line where it lies beyond the straight
    leg (a correction must never ask for more leg than there is); its rotation unchanged."""
    ankle = sole + rot @ np.array([0.0, 0.0, leg.ankle_to_sole])
    span = ankle - leg.hip
    reach = (leg.thigh + leg.calf) * REACH_SHARE
    length = float(np.linalg.norm(span))
    if length <= reach:
        return sole, rot
    return sole - span * (1.0 - reach / length), rot


def _swing_phase(contact: tuple[str, ...]) -> np.ndarray:
    """Per row (K,): 0 -> 1 across each single-support phase (0 on both feet)."""
    phase = np.zeros(len(contact))
    start = 0
    for i in range(1, len(contact) + 1):
        if i == len(contact) or contact[i] != contact[start]:
            if contact[start] != "double":
                phase[start:i] = np.linspace(1.0 / (i - start), 1.0, i - start)
            start = i
    return phase


@dataclass
class _State:
    attitude: np.ndarray = field(default_factory=lambda: np.zeros(2))     # estimated pitch, roll [rad]
    integral: np.ndarray = field(default_factory=lambda: np.zeros(2))     # of the attitude error [rad·s]
    yaw: float = 0.0                                                        # integrated gyro z [rad]
    joint_integral: np.ndarray | None = None                                # leg goal trims (20,) [rad]
    started: bool = False


class WalkController:
    """A planned gait played with attitude stabilisation (see the module docstring)."""

    def __init__(self, gait: Gait, spec: Spec, feedback: Feedback = Feedback()):
        self.gait, self.spec, self.feedback = gait, spec, feedback
        self.plan: Plan = gait_plan(gait)
        self.schedule = Schedule(self.plan, spec.joint_names)
        self.lead = len(self.plan.goals) - len(gait.goals)
        self.legs = {side: leg_of(spec, side) for side in SIDES}
        self.leg_index = np.array(sorted(i for leg in self.legs.values() for i in leg.index))
        self.plan_yaw = np.unwrap(np.arctan2(gait.torso_rot[:, 1, 0], gait.torso_rot[:, 0, 0]))   # turns pass ±180°
        self.swing_phase = _swing_phase(gait.timeline.contact)
        self.state = _State()

    @classmethod
    def from_preset(cls, preset: str | None = None, steps: int | None = None, spec: Spec | None = None,
                    feedback: Feedback = Feedback()) -> "WalkController":
        """The controller of a preset (a shipped name or a file; default ``forward``) with ``steps`` steps."""
        from op2motion.robot.specfile import default_spec

        spec = spec or default_spec()
        from op2motion.gait.speeds import plan_within_speed

        return cls(plan_within_speed(load_preset(preset).with_steps(steps), spec), spec, feedback)

    @property
    def done(self) -> bool:
        """Never: after the plan's last row the stabiliser keeps balancing the pose it holds."""
        return False

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """Reset the estimator and the integrals; the plan's first goals."""
        self.state = _State()
        return dict(self.schedule.start(joint_positions))

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The goals at ``t_s`` [s]: the plan's, with the body turned against the torso's attitude error."""
        row = self.plan.row(t_s)
        k = max(row - self.lead, 0)                       # the gait's own row (its first during the lead-in)
        gyro = np.array([gyro_rad_s[1], gyro_rad_s[0]])   # pitch rate (about y), roll rate (about x)
        error = self._estimate(gyro, np.asarray(accel_m_s2, dtype=float), k)
        f = self.feedback
        turn = -(np.multiply(f.kp, error) + np.multiply(f.ki, self.state.integral) + np.multiply(f.kd, gyro))
        turn = np.clip(turn, -MAX_CORRECTION_RAD, MAX_CORRECTION_RAD)
        goals = self.schedule.goals_at(t_s).copy()
        goals += self._damping(np.asarray(gyro_rad_s, dtype=float))
        self.state.yaw += float(gyro_rad_s[2]) * CONTROL_PERIOD_S
        heading = float(np.clip(-f.heading * (self.state.yaw - self.plan_yaw[k]), -MAX_HEADING_RAD, MAX_HEADING_RAD))
        if np.any(turn) or heading:
            goals += self._leg_change(k, float(turn[0]), float(turn[1]), heading)
        if f.joint_ki and row >= self.lead:
            goals += self._joint_trim(k, joint_positions)
        return dict(zip(self.spec.joint_names, goals.tolist()))

    def _joint_trim(self, k: int, joint_positions: Mapping[str, float]) -> np.ndarray:
        """The legs' integral trims (20,) [rad]: what the servos' sag keeps them from the planned angles, added to
        their goals little by little (``joint_ki`` [1/s])."""
        s = self.state
        if s.joint_integral is None:
            s.joint_integral = np.zeros(len(self.spec.joints))
        measured = np.array([joint_positions[self.spec.joint_names[i]] for i in self.leg_index])
        error = self.gait.joints[k, self.leg_index] - measured
        trim = s.joint_integral[self.leg_index] + self.feedback.joint_ki * error * CONTROL_PERIOD_S
        s.joint_integral[self.leg_index] = np.clip(trim, -MAX_TRIM_RAD, MAX_TRIM_RAD)
        return s.joint_integral

    def _estimate(self, gyro: np.ndarray, accel: np.ndarray, k: int) -> np.ndarray:
        """Update the attitude estimate and the error integral; the error [rad] (pitch, roll) against the plan."""
        s, dt = self.state, CONTROL_PERIOD_S
        measured = np.array([math.atan2(-accel[0], accel[2]), math.atan2(accel[1], math.hypot(accel[0], accel[2]))])
        if not s.started:
            s.attitude, s.started = measured, True
        blend = dt / (self.feedback.attitude_tau_s + dt)
        s.attitude = (1.0 - blend) * (s.attitude + gyro * dt) + blend * measured
        error = s.attitude - attitude_of(self.gait.torso_rot[k])
        s.integral = np.clip(s.integral + error * dt, -MAX_CORRECTION_RAD, MAX_CORRECTION_RAD)
        return error

    def _damping(self, gyro: np.ndarray) -> np.ndarray:
        """The stock-style gyro damping (20,) [rad]: each leg's hip roll, knee, ankle pitch and ankle roll turned so
        that the body turns against its rate (natural angles, both legs)."""
        hip_roll, knee, ankle_pitch, ankle_roll = self.feedback.gyro
        natural = np.array([0.0, hip_roll * gyro[0], 0.0, knee * gyro[1], ankle_pitch * gyro[1], ankle_roll * gyro[0]])
        out = np.zeros(len(self.spec.joints))
        for leg in self.legs.values():
            out[list(leg.index)] = natural * leg.sign
        return out

    def _support_point(self, k: int) -> np.ndarray:
        feet = self.gait.timeline.feet
        sides = Support.of(self.gait.timeline.contact[k]).feet
        return np.mean([feet[side][k, :3] for side in sides], axis=0)

    def _leg_change(self, k: int, pitch: float, roll: float, heading: float = 0.0) -> np.ndarray:
        """The servo change (20,) [rad] that turns the whole body by (pitch, roll) [rad] about the support point,
        the soles staying where the plan puts them, and the swing sole turned by ``heading`` [rad] about the stance
        sole's centre (in full at landing)."""
        pos, rot = self.gait.torso_pos[k], self.gait.torso_rot[k]
        pivot, turn = self._support_point(k), rot_y(pitch) @ rot_x(roll)
        moved_pos, moved_rot = pivot + turn @ (pos - pivot), turn @ rot
        contact = self.gait.timeline.contact[k]
        out = np.zeros(len(self.spec.joints))
        for side, leg in self.legs.items():
            planned_sole, planned_rot = self.gait.timeline.feet[side][k, :3], rot_z(self.gait.timeline.feet[side][k, 3])
            sole, sole_rot = planned_sole, planned_rot
            if contact not in ("double", side) and heading:
                steer = rot_z(heading * self.swing_phase[k])
                stance = self.gait.timeline.feet[contact][k, :3]
                sole, sole_rot = stance + steer @ (sole - stance), steer @ sole_rot
            planned = leg_ik(leg, *_within_reach(leg, rot.T @ (planned_sole - pos), rot.T @ planned_rot))[0]
            moved = leg_ik(leg, *_within_reach(leg, moved_rot.T @ (sole - moved_pos), moved_rot.T @ sole_rot))[0]
            out[list(leg.index)] = moved - planned
        return out
