"""A walk that reacts: the ZMP preview plan played every 8 ms with stabilisation from the robot's IMU and joints.

:class:`WalkController` is a :class:`~op2motion.physics.Controller`: the physics check drives it, and so can a
robot bridge or another simulator, with the torso's gyro [rad/s] and accelerometer [m/s²] (torso frame: x forward,
y left, z up; the accelerometer reads +9.81 m/s² on z when upright and still) and the joint positions every 8 ms.
Inside, per tick (gains in :class:`Feedback`):

1. **the plan** (:func:`.schedule.gait_plan`): the goals of this row (servo feed-forward included), the planned
   torso pose and soles;
2. **gyro damping** as in the stock gait: hip roll and ankle roll against the roll rate, knee and ankle pitch
   against the pitch rate (0.6 of the stock gains, up to all of them as the servos' measured softness grows);
3. **attitude**: a complementary filter of the gyro and the gravity in the accelerometer (low-passed as a vector
   first: the tilt of each raw sample, with the impacts of the steps in it, averaged 3–6° off while walking) estimates
   pitch and roll; against the plan's, the error (P, and optionally its integral) turns the whole body about the
   support point (legs by the closed-form IK, soles where the plan puts them). The P gain follows the servos'
   measured softness (:mod:`.calibration`): soft servos let the body tip without it, stiff ones oscillate with it;
4. **heading and line**: the integrated yaw rate against the plan's heading, plus the sideways error dead-reckoned
   from it (the plan's stride velocity turned by the heading error), steer the swing foot about the stance foot
   (PI, in full at landing); leg odometry (:mod:`.odometry`) measures each landing from the joints and moves the
   next swing foot against the feet's error across the direction of travel, and holds the closing foot where it
   landed;
5. **the servos**: their stiffness measured while the robot stands before the first step, and the feed-forward a
   softer servo lacks added (:mod:`.calibration`); slow integral trims of the legs' sag; the swing leg's
   feed-forward learnt from the steps before (:mod:`.learning`), so the swing foot lands where planned whatever the
   servos' real stiffness.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from op2motion.gait.calibration import StiffnessCalibration
from op2motion.gait.feedback import GYRO_GAINS_S, OPEN_LOOP, STOCK_GYRO_GAINS_S, Feedback
from op2motion.gait.generator import Gait
from op2motion.gait.learning import StepLearner
from op2motion.gait.odometry import FootOdometry, left_of
from op2motion.gait.presets import load_preset
from op2motion.gait.schedule import gait_plan
from op2motion.kinematics.leg_ik import leg_ik, leg_of, rot_x, rot_y, rot_z, within_reach
from op2motion.physics import Plan, Schedule
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES, Support

REACH_SHARE = 0.999                # a corrected leg stretches at most to this share of its length
MAX_HEADING_RAD = 0.2             # the swing foot is steered at most this far per step (11°)
MAX_TRIM_RAD = 0.15                # a leg joint's integral trim stays within this [rad] (8.6°)
MAX_CORRECTION_RAD = 0.25          # the stabiliser turns the body at most this far (14°)
LANDING_ROWS = 2                   # a landing is measured this many rows past the latency into its double support


def attitude_of(rot: np.ndarray) -> np.ndarray:
    """Pitch and roll [rad] of a torso rotation: the tilt of its z axis towards +x (pitch: leaning forward > 0) and
    towards -y (roll: turned about +X > 0)."""
    z = rot[:, 2]
    return np.array([math.atan2(z[0], z[2]), math.atan2(-z[1], math.hypot(z[0], z[2]))])


def _stride_velocity(gait: Gait) -> np.ndarray:
    """Per row (K, 2): the plan's torso velocity [m/s] averaged over a stride (two steps), the sway left out."""
    rows = max(1, int(round(2.0 * (gait.params.single_s + gait.params.double_s) / CONTROL_PERIOD_S)))
    velocity = np.gradient(gait.torso_pos[:, :2], CONTROL_PERIOD_S, axis=0)
    kernel = np.ones(rows) / rows
    return np.stack([np.convolve(velocity[:, i], kernel, mode="same") for i in range(2)], axis=1)


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


__all__ = ["Feedback", "GYRO_GAINS_S", "OPEN_LOOP", "STOCK_GYRO_GAINS_S", "WalkController", "attitude_of"]


@dataclass
class _State:
    attitude: np.ndarray = field(default_factory=lambda: np.zeros(2))     # estimated pitch, roll [rad]
    integral: np.ndarray = field(default_factory=lambda: np.zeros(2))     # of the attitude error [rad·s]
    yaw: float = 0.0                                                        # integrated gyro z [rad]
    yaw_integral: float = 0.0                                               # of the heading error [rad·s]
    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))       # dead-reckoned position error [m]
    joint_integral: np.ndarray | None = None                                # leg goal trims (20,) [rad]
    intended: list[np.ndarray] = field(default_factory=list)                # recent intended joints (20,) [rad]
    started: bool = False
    accel: np.ndarray | None = None


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
        self.plan_velocity = _stride_velocity(gait)
        self.learner = StepLearner.of(gait, {side: np.array(leg.index) for side, leg in self.legs.items()},
                                      feedback.learn_gain, feedback.learn_shift_rows)
        self.delay_rows = int(round(feedback.latency_s / CONTROL_PERIOD_S))
        self.calibration = StiffnessCalibration.of(gait, self.leg_index)
        self.odometry = FootOdometry.of(gait, self.legs, self.delay_rows + LANDING_ROWS)
        self.sole_rots = {side: rot_z(gait.timeline.feet[side][:, 3]) for side in SIDES}   # (K, 3, 3) each
        self.planned_legs = self._planned_legs()
        self.support_points = self._support_points()
        self.state = _State()

    def _planned_legs(self) -> dict[str, np.ndarray]:
        """Each leg's servo angles (K, 6) [rad] that put its sole where the plan does, every gait row (the
        reference :meth:`_leg_change` turns from; worked out once, in one batch)."""
        pos, rot = self.gait.torso_pos, self.gait.torso_rot
        out = {}
        for side, leg in self.legs.items():
            feet = self.gait.timeline.feet[side]
            sole = np.einsum("kji,kj->ki", rot, feet[:, :3] - pos)                    # rot.T @ (sole - pos)
            sole_rot = np.swapaxes(rot, 1, 2) @ self.sole_rots[side]
            out[side] = leg_ik(leg, *within_reach(leg, sole, sole_rot, REACH_SHARE))
        return out

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
        self.learner.reset()
        self.calibration.reset()
        self.odometry.reset()
        return dict(self.schedule.start(joint_positions))

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The goals at ``t_s`` [s]: the plan's, with the body turned against the torso's attitude error."""
        row = self.plan.row(t_s)
        k = max(row - self.lead, 0)                       # the gait's own row (its first during the lead-in)
        gyro = np.array([gyro_rad_s[1], gyro_rad_s[0]])   # pitch rate (about y), roll rate (about x)
        error = self._estimate(gyro, np.asarray(accel_m_s2, dtype=float), k)
        f = self.feedback
        kp = np.add(f.kp, np.multiply(f.soft_kp, self.calibration.softness))
        turn = -(kp * error + np.multiply(f.ki, self.state.integral) + np.multiply(f.kd, gyro))
        turn = np.clip(turn, -MAX_CORRECTION_RAD, MAX_CORRECTION_RAD)
        change = self._damping(np.asarray(gyro_rad_s, dtype=float))
        heading = self._heading(float(gyro_rad_s[2]), k)
        if np.any(turn) or heading or f.placement or f.accept_landing:
            change += self._leg_change(k, float(turn[0]), float(turn[1]), heading)
        goals = self.schedule.goals_at(t_s) + change
        if row >= self.lead:
            measured = np.array([joint_positions[name] for name in self.spec.joint_names])
            self._remember(k, self.gait.joints[k] + change, measured)
            if f.placement or f.accept_landing:
                self.odometry.observe(k, measured)
            if f.joint_ki:
                goals += self._joint_trim(k, measured)
            goals += self.learner.correction(k)
            if f.calibrate:
                self.calibration.observe(k, self.schedule.goals_at(t_s), measured)
                goals += self.calibration.compensation(k, len(goals))
        return dict(zip(self.spec.joint_names, goals.tolist()))

    def _remember(self, k: int, intended: np.ndarray, measured: np.ndarray) -> None:
        """Keep this row's intended joints; teach the learner what the joints (measured ``delay_rows`` late)
        missed."""
        history = self.state.intended
        history.append(intended)
        del history[:-(self.delay_rows + 1)]
        if self.feedback.learn_gain and len(history) == self.delay_rows + 1:
            self.learner.learn(k - self.delay_rows, history[0] - measured)

    def _heading(self, yaw_rate: float, k: int) -> float:
        """The swing foot's steer [rad]: a PI loop on the heading error (integrated gyro yaw less the plan's),
        whose target leans back towards the planned line by ``cross_track`` [rad/m] of the dead-reckoned sideways
        error (the plan's stride velocity turned by the heading error, integrated)."""
        s, f, dt = self.state, self.feedback, CONTROL_PERIOD_S
        s.yaw += yaw_rate * dt
        error = s.yaw - self.plan_yaw[k]
        velocity = self.plan_velocity[k]
        s.offset += (rot_z(error)[:2, :2] @ velocity - velocity) * dt
        left = left_of(velocity)
        if left is not None:
            error += f.cross_track * float(s.offset @ left)
        s.yaw_integral = float(np.clip(s.yaw_integral + error * dt, -MAX_HEADING_RAD, MAX_HEADING_RAD))
        return float(np.clip(-f.heading * error - f.heading_ki * s.yaw_integral, -MAX_HEADING_RAD, MAX_HEADING_RAD))

    def _joint_trim(self, k: int, measured_all: np.ndarray) -> np.ndarray:
        """The legs' integral trims (20,) [rad]: what the servos' sag keeps them from the planned angles, added to
        their goals little by little (``joint_ki`` [1/s])."""
        s = self.state
        if s.joint_integral is None:
            s.joint_integral = np.zeros(len(self.spec.joints))
        measured = measured_all[self.leg_index]
        error = self.gait.joints[k, self.leg_index] - measured
        trim = s.joint_integral[self.leg_index] + self.feedback.joint_ki * error * CONTROL_PERIOD_S
        s.joint_integral[self.leg_index] = np.clip(trim, -MAX_TRIM_RAD, MAX_TRIM_RAD)
        return s.joint_integral

    def _estimate(self, gyro: np.ndarray, accel: np.ndarray, k: int) -> np.ndarray:
        """Update the attitude estimate and the error integral; the error [rad] (pitch, roll) against the plan."""
        s, dt = self.state, CONTROL_PERIOD_S
        if self.feedback.accel_tau_s:
            if s.accel is None:
                s.accel = accel.copy()
            s.accel = s.accel + dt / (self.feedback.accel_tau_s + dt) * (accel - s.accel)
            accel = s.accel
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
        scale = 1.0 + self.feedback.soft_gyro * self.calibration.softness        # soft servos: more damping
        hip_roll, knee, ankle_pitch, ankle_roll = np.multiply(self.feedback.gyro, scale)
        natural = np.array([0.0, hip_roll * gyro[0], 0.0, knee * gyro[1], ankle_pitch * gyro[1], ankle_roll * gyro[0]])
        out = np.zeros(len(self.spec.joints))
        for leg in self.legs.values():
            out[list(leg.index)] = natural * leg.sign
        return out

    def _support_points(self) -> np.ndarray:
        """The point (K, 3) [m] the body turns about at each gait row: the planned contact sole's centre, midway
        between the soles on two feet."""
        feet = self.gait.timeline.feet
        return np.array([np.mean([feet[side][k, :3] for side in Support.of(contact).feet], axis=0)
                         for k, contact in enumerate(self.gait.timeline.contact)])

    def _leg_change(self, k: int, pitch: float, roll: float, heading: float = 0.0) -> np.ndarray:
        """The servo change (20,) [rad] that turns the whole body by (pitch, roll) [rad] about the support point,
        the soles staying where the plan puts them, and the swing sole turned by ``heading`` [rad] about the stance
        sole's centre (in full at landing) and moved against the feet's placement error (leg odometry); after the
        closing step, the landed sole where it landed."""
        pos, rot = self.gait.torso_pos[k], self.gait.torso_rot[k]
        pivot, turn = self.support_points[k], rot_y(pitch) @ rot_x(roll)
        moved_pos, moved_rot = pivot + turn @ (pos - pivot), turn @ rot
        contact = self.gait.timeline.contact[k]
        out = np.zeros(len(self.spec.joints))
        for side, leg in self.legs.items():
            sole, sole_rot = self.gait.timeline.feet[side][k, :3], self.sole_rots[side][k]
            if contact not in ("double", side) and heading:
                steer = rot_z(heading * self.swing_phase[k])
                stance = self.gait.timeline.feet[contact][k, :3]
                sole, sole_rot = stance + steer @ (sole - stance), steer @ sole_rot
            last = self.odometry.last
            if self.feedback.accept_landing and last is not None and last[0] == side:
                sole, sole_rot = sole + np.array([*last[1], 0.0]), rot_z(last[2]) @ sole_rot
            if contact not in ("double", side) and self.feedback.placement:
                sole = sole + self.swing_phase[k] * self.odometry.shift(self.feedback.placement, self.plan_velocity[k])
            planned = self.planned_legs[side][k]
            moved = leg_ik(leg, *within_reach(leg, moved_rot.T @ (sole - moved_pos), moved_rot.T @ sole_rot,
                                              REACH_SHARE))[0]
            out[list(leg.index)] = moved - planned
        return out
