"""A walk that reacts: the ZMP preview plan played every 8 ms with stabilisation from the robot's IMU and joints.

:class:`StabilisedWalk` is what both walks share (the planned :class:`.controller.WalkController` and the steered
:class:`.steer.SteerableWalk`): a :class:`~op2motion.physics.Controller`: the physics check drives it, and so can a
robot bridge or another simulator, with the torso's gyro [rad/s] and accelerometer [m/s²] (torso frame: x forward,
y left, z up; the accelerometer reads +9.81 m/s² on z when upright and still) and the joint positions every 8 ms.
Inside, per tick (gains in :class:`Feedback`):

1. **the plan** (:func:`.schedule.plan_of_gait`): the goals of this row (servo feed-forward included), the planned
   torso pose and soles;
2. **gyro damping** as in the stock gait: hip roll and ankle roll against the roll rate, knee and ankle pitch
   against the pitch rate (0.6 of the stock gains, up to all of them as the servos' measured softness grows; a
   preset's ``gyro_stiff_share`` lowers them on servos measured stiffer than the model);
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
   servos' real stiffness;
6. **the swing foot's attitude** (a preset's ``swing_level``, ``swing_level_roll``, ``swing_toe_deg``, off by
   default): the swing sole kept level and at its planned place in the world however the torso tilts, its toe
   raised over the floor (:mod:`.swing_foot`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Mapping, Self, Sequence

import numpy as np

from op2motion.gait.calibration import PlannedCalibration, StiffnessCalibration
from op2motion.gait.feedback import GYRO_GAINS_S, OPEN_LOOP, STOCK_GYRO_GAINS_S, Feedback
from op2motion.gait.generator import Gait
from op2motion.gait.learning import PlannedLearner, StepLearner
from op2motion.gait.leg_targets import LegTargets
from op2motion.gait.odometry import FootOdometry, PlannedOdometry, left_of
from op2motion.gait.phases import Intent
from op2motion.gait.planned_stop import splice_row, stop_planner
from op2motion.gait.presets import load_preset
from op2motion.gait.rows import RowBuffer, rows_of_gait, swing_phase
from op2motion.gait.schedule import plan_of_gait
from op2motion.gait.steer_feedback import RollingCalibration, RollingOdometry
from op2motion.kinematics.leg_ik import leg_of
from op2motion.motion.stillness import Stillness
from op2motion.physics import Plan, Schedule
from op2motion.robot.controller import ControllerHooks
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import SIDES

if TYPE_CHECKING:
    from op2motion.gait.rolling import RollingPlanner

MAX_HEADING_RAD = 0.2             # the swing foot is steered at most this far per step (11°)
MAX_TRIM_RAD = 0.15                # a leg joint's integral trim stays within this [rad] (8.6°)
MAX_CORRECTION_RAD = 0.25          # the stabiliser turns the body at most this far (14°)
STIFF_FROM = 1.1                   # servos measured this much stiffer than the model begin to lose the standing damping
STIFF_FULL = 1.25                  # ... and lose all of it from here on (the family's x1.6 servos read 1.28)
LANDING_ROWS = 2                   # a landing is measured this many rows past the latency into its double support
STOPPED_SETTLE_S = 0.4             # a walk stopped early is done this long after the step that closed its feet [s]: its
                                   # CoM on its way back between them, on both feet (waiting until it is still took
                                   # 0.6 s more, and Ctrl-C must end the command within 3 s)


def attitude_of(rot: np.ndarray) -> np.ndarray:
    """Pitch and roll [rad] of a torso rotation: the tilt of its z axis towards +x (pitch: leaning forward > 0) and
    towards -y (roll: turned about +X > 0)."""
    return np.array(_attitude(rot))


def _attitude(rot: np.ndarray) -> tuple[float, float]:
    """:func:`attitude_of` as two floats (per tick)."""
    x, y, z = rot[:, 2].tolist()
    return math.atan2(x, z), math.atan2(-y, math.hypot(x, z))


def _clip(value: float, bound: float) -> float:
    """``value`` within ±``bound`` (``np.clip`` on one float costs microseconds)."""
    return min(max(value, -bound), bound)


_swing_phase = swing_phase           # the name the tests knew


def _stopping() -> Intent:
    """What a planned walk stopped early asks of its planner: to stop."""
    return Intent(stop=True)


__all__ = ["Feedback", "GYRO_GAINS_S", "OPEN_LOOP", "STOCK_GYRO_GAINS_S", "StabilisedWalk", "attitude_of"]


@dataclass
class _State:
    """The stabiliser's memory; pairs are (pitch, roll) or (x, y), as floats (the per-tick arithmetic is scalar)."""

    attitude: tuple[float, float] = (0.0, 0.0)                              # estimated pitch, roll [rad]
    integral: tuple[float, float] = (0.0, 0.0)                              # of the attitude error [rad·s]
    yaw: float = 0.0                                                        # integrated gyro z [rad]
    yaw_integral: float = 0.0                                               # of the heading error [rad·s]
    offset: tuple[float, float] = (0.0, 0.0)                                # dead-reckoned position error [m]
    joint_integral: np.ndarray | None = None                                # leg goal trims (20,) [rad]
    intended: list[np.ndarray] = field(default_factory=list)                # recent intended joints (20,) [rad]
    started: bool = False
    accel: tuple[float, float, float] | None = None                         # low-passed accelerometer [m/s²]
    error: tuple[float, float] = (0.0, 0.0)                                 # last attitude error (pitch, roll) [rad]


class StabilisedWalk(LegTargets, ControllerHooks):
    """A gait's rows played with attitude stabilisation (see the module docstring; the legs' goals for a turned
    body and moved soles: :class:`.leg_targets.LegTargets`): built on a planned gait, or by
    :class:`.steer.SteerableWalk` on rows it plans while it walks.

    ``done`` says when the walk is over: its plan has run out (the last row held) and the body has kept still for
    :data:`op2motion.motion.stillness.STILL_S` (then the servos may hold the last goals); until then the stabiliser
    keeps balancing. :meth:`stop` ends it early, on both feet side by side (:mod:`.planned_stop`).
    The walk you steer while it walks is :class:`.steer.SteerableWalk`."""

    stops_itself = True

    def __init__(self, gait: Gait, spec: Spec, feedback: Feedback = Feedback()):
        self.gait, self.spec, self.feedback, self.params = gait, spec, feedback, gait.params
        self.plan: Plan = plan_of_gait(gait)
        self.schedule = Schedule(self.plan, spec.joint_names)
        self.lead = len(self.plan.goals) - len(gait.goals)
        self._setup_legs(spec, feedback)
        self.rows: RowBuffer = rows_of_gait(gait, self.legs)
        self.learner: StepLearner = PlannedLearner.of(gait, dict(self._leg_servos), feedback.learn_gain,
                                                      feedback.learn_shift_rows)
        self.calibration: StiffnessCalibration = PlannedCalibration.of(gait, self.leg_index)
        self.odometry: FootOdometry = PlannedOdometry.of(gait, self.legs, self.delay_rows + LANDING_ROWS)

    def _setup_legs(self, spec: Spec, feedback: Feedback) -> None:
        """What both kinds of walk share: the legs, the latency in rows, the state."""
        self.legs = {side: leg_of(spec, side) for side in SIDES}
        self.leg_index = np.array(sorted(i for leg in self.legs.values() for i in leg.index))
        self._leg_servos = {side: np.array(leg.index) for side, leg in self.legs.items()}    # index once, not per tick
        self._both_legs = np.concatenate(list(self._leg_servos.values()))
        self._both_signs = np.concatenate([leg.sign for leg in self.legs.values()])
        self._names = spec.joint_names
        self.delay_rows = int(round(feedback.latency_s / CONTROL_PERIOD_S))
        self.state = _State()
        self.stillness = Stillness()
        self._k = -1
        self.stopper: RollingPlanner | None = None        # plans the rest of a planned walk stopped early
        self.stopped_from: int | None = None              # the gait row it plans from
        self.held_row: int | None = None                  # the gait row a walk stopped before its first step holds

    @property
    def plan_yaw(self) -> np.ndarray:
        """The planned heading of every row kept (K,) [rad], unwrapped."""
        return self.rows.numeric["plan_yaw"]

    @classmethod
    def from_preset(cls, preset: str | None = None, steps: int | None = None, spec: Spec | None = None,
                    feedback: Feedback = Feedback()) -> Self:
        """The controller of a preset (a shipped name or a file; default ``forward``) with ``steps`` steps."""
        from op2motion.robot.specfile import default_spec

        spec = spec or default_spec()
        from op2motion.gait.speeds import gait_within_speed

        return cls(gait_within_speed(load_preset(preset).with_steps(steps), spec), spec, feedback)

    @property
    def done(self) -> bool:
        """The plan has run out and the body has kept still (see the class docstring); stopped early, once the feet
        are closed and it has stood on both :data:`STOPPED_SETTLE_S` (the servos hold it there)."""
        if self.stopper is not None:
            ends = [first for first, phase in self.stopper.phases if phase.kind == "end"]
            return bool(ends) and self._k >= ends[0] + int(round(STOPPED_SETTLE_S / CONTROL_PERIOD_S))
        return self._plan_over(self._k) and self.stillness.still

    def _plan_over(self, k: int) -> bool:
        """Has the plan run out at gait row ``k``? (Stopped before the first step: at once.)"""
        return self.held_row is not None or k >= self.rows.end - 1

    def stop(self) -> None:
        """End the walk early (:mod:`.planned_stop`): from the next step that can still be planned again, a step
        at half the stride and the one that closes the feet, then standing; before the first step, held where it
        is (on both feet); :attr:`done` once still. The leg odometry measures on; the step learner's corrections
        end there (a closing step learns nothing)."""
        if self.stopper is not None or self.held_row is not None:
            return
        at = splice_row(self.gait, self._k)
        if at is None:
            return
        if at[0] == 0:
            self.held_row = max(self._k, 0)
            return
        self.stopped_from, self.stopper = at[1], stop_planner(self.gait, self.spec, self.legs, self.rows, *at)
        calibration = RollingCalibration.rolling(self.rows, self.leg_index, self.calibration.first_step)
        calibration.start_row, calibration.end_row = self.calibration.start_row, self.calibration.end_row
        calibration.sums = self.calibration.sums
        self.calibration = calibration

    def _stopping_rows(self, k: int) -> None:
        """Stopped early: plan on (a stage a tick) and, at the first row planned again, measure the landings
        where the new rows say they happen."""
        if self.stopper is None or self.stopped_from is None or k < 0:
            return
        self.stopper.tick(k, _stopping)
        if k >= self.stopped_from and not isinstance(self.odometry, RollingOdometry):
            odometry = RollingOdometry.rolling(self.rows, self.legs, self.delay_rows + LANDING_ROWS)
            odometry.error, odometry.last = self.odometry.error, self.odometry.last
            self.odometry = odometry

    def _row(self, t_s: float) -> int:
        """The gait row of time ``t_s`` [s] (negative during the lead-in)."""
        return self.plan.row(t_s) - self.lead

    def _planned_goals(self, t_s: float, k: int) -> np.ndarray:
        """The plan's goals (20,) [rad] at ``t_s`` (gait row ``k``)."""
        if self.stopped_from is not None and k >= self.stopped_from:
            return self.rows.get("goals", k).copy()
        if self.held_row is not None:
            return self.rows.get("goals", self.held_row).copy()
        return self.schedule.goals_at(t_s)

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """Reset the estimator and the integrals; the plan's first goals."""
        self.state = _State()
        self.stillness = Stillness()
        self._k = -1
        self.learner.reset()
        self.calibration.reset()
        self.odometry.reset()
        return dict(zip(self._names, self._planned_goals(0.0, self._row(0.0)).tolist()))

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """The goals at ``t_s`` [s]: the plan's, with the body turned against the torso's attitude error."""
        row = self._row(t_s)
        if self.held_row is not None:
            row = min(row, self.held_row)
        k = max(row, 0)                                   # the gait's own row (its first during the lead-in)
        self._k = row
        if self.stopper is not None:
            self._stopping_rows(row)
        measured = np.array([joint_positions[name] for name in self._names])
        gyro_xyz = np.asarray(gyro_rad_s, dtype=float)
        self.stillness.update(gyro_xyz, measured)
        roll_rate, pitch_rate, yaw_rate = gyro_xyz.tolist()
        error = self._estimate((pitch_rate, roll_rate), accel_m_s2, k)
        self.state.error = error
        turn = self._turn(error, (pitch_rate, roll_rate))
        change = self._damping(gyro_xyz) * self._standing_share(k)
        heading = self._heading(yaw_rate, k)
        f = self.feedback
        if turn[0] or turn[1] or heading or f.placement or f.accept_landing or self._swing_shaped:
            change += self._leg_change(k, turn[0], turn[1], heading)
        planned = self._planned_goals(t_s, row)
        if row >= 0 and self.rows.value("open", k):
            return dict(zip(self._names, planned.tolist()))      # a kick inside a walk: as planned
        goals = planned + change
        if row >= 0:
            self._remember(k, self.rows.get("joints", k) + change, measured)
            if f.placement or f.accept_landing:
                self.odometry.observe(k, measured)
            if f.joint_ki:
                goals += self._joint_trim(k, measured)
            if self.stopped_from is None or k < self.stopped_from:
                goals += self.learner.correction(k)
            if f.calibrate:
                self.calibration.observe(k, planned, measured)
                goals += self.calibration.compensation(k, len(goals))
        return dict(zip(self._names, goals.tolist()))

    def _turn(self, error: tuple[float, float], rates: tuple[float, float]) -> tuple[float, float]:
        """The body's turn (pitch, roll) [rad] against the attitude ``error`` [rad], its integral and the ``rates``
        [rad/s] (P gain scheduled by the servos' softness), bounded."""
        f, soft, integral = self.feedback, self.calibration.softness, self.state.integral
        pitch, roll = (_clip(-((f.kp[i] + f.soft_kp[i] * soft) * error[i] + f.ki[i] * integral[i] + f.kd[i] * rates[i]),
                             MAX_CORRECTION_RAD) for i in range(2))
        return pitch, roll

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
        error = s.yaw - self.rows.value("plan_yaw", k)
        velocity = self.rows.get("velocity", k)
        vx, vy = velocity.tolist()
        c, si = math.cos(error), math.sin(error)                               # the velocity turned by the error
        s.offset = (s.offset[0] + ((c * vx - si * vy) - vx) * dt, s.offset[1] + ((si * vx + c * vy) - vy) * dt)
        left = left_of(velocity)
        if left is not None:
            error += f.cross_track * float(s.offset[0] * left[0] + s.offset[1] * left[1])
        s.yaw_integral = _clip(s.yaw_integral + error * dt, MAX_HEADING_RAD)
        gain = self.params.heading_gain_scale                                   # the preset's tuning
        return _clip(-gain * (f.heading * error + f.heading_ki * s.yaw_integral), MAX_HEADING_RAD)

    def _joint_trim(self, k: int, measured_all: np.ndarray) -> np.ndarray:
        """The legs' integral trims (20,) [rad]: what the servos' sag keeps them from the planned angles, added to
        their goals little by little (``joint_ki`` [1/s])."""
        s = self.state
        if s.joint_integral is None:
            s.joint_integral = np.zeros(len(self.spec.joints))
        measured = measured_all[self.leg_index]
        error = self.rows.get("joints", k)[self.leg_index] - measured
        trim = s.joint_integral[self.leg_index] + self.feedback.joint_ki * error * CONTROL_PERIOD_S
        s.joint_integral[self.leg_index] = np.minimum(np.maximum(trim, -MAX_TRIM_RAD), MAX_TRIM_RAD)   # np.clip
        trims: np.ndarray = s.joint_integral
        return trims

    def _estimate(self, gyro: Sequence[float], accel: np.ndarray | Sequence[float], k: int) -> tuple[float, float]:
        """Update the attitude estimate and the error integral from the (pitch, roll) rates [rad/s] and the
        accelerometer (3,) [m/s²]; the error [rad] (pitch, roll) against the plan."""
        s, dt = self.state, CONTROL_PERIOD_S
        ax, ay, az = np.asarray(accel, dtype=float).tolist()
        if self.feedback.accel_tau_s:
            if s.accel is None:
                s.accel = (ax, ay, az)
            w = dt / (self.feedback.accel_tau_s + dt)
            mx, my, mz = s.accel
            ax, ay, az = mx + w * (ax - mx), my + w * (ay - my), mz + w * (az - mz)
            s.accel = (ax, ay, az)
        measured = (math.atan2(-ax, az), math.atan2(ay, math.hypot(ax, az)))
        if not s.started:
            s.attitude, s.started = measured, True
        blend = dt / (self.feedback.attitude_tau_s + dt)
        rates = (float(gyro[0]), float(gyro[1]))
        s.attitude = ((1.0 - blend) * (s.attitude[0] + rates[0] * dt) + blend * measured[0],
                      (1.0 - blend) * (s.attitude[1] + rates[1] * dt) + blend * measured[1])
        planned = _attitude(self.rows.get("torso_rot", k))
        error = (s.attitude[0] - planned[0], s.attitude[1] - planned[1])
        s.integral = (_clip(s.integral[0] + error[0] * dt, MAX_CORRECTION_RAD),
                      _clip(s.integral[1] + error[1] * dt, MAX_CORRECTION_RAD))
        return error

    def _standing_share(self, k: int) -> float:
        """The share of the gyro damping at gait row ``k``: all of it, except where the plan stands still after
        walking (the rows' ``damping`` fades to 0 there) and the servos were measured stiffer than the model: with
        servos 1.6 times as stiff and 16 ms of latency the damping kept a standing robot rocking, while soft servos
        need it to stand (taken out for them, the heavy, soft body fell over standing)."""
        stiff = min(max((self.calibration.estimate - STIFF_FROM) / (STIFF_FULL - STIFF_FROM), 0.0), 1.0)
        return 1.0 - (1.0 - self.rows.value("damping", k)) * stiff

    def _damping(self, gyro: np.ndarray) -> np.ndarray:
        """The stock-style gyro damping (20,) [rad]: each leg's hip roll, knee, ankle pitch and ankle roll turned so
        that the body turns against its rate (natural angles, both legs)."""
        scale = 1.0 + self.feedback.soft_gyro * self.calibration.softness        # soft servos: more damping
        scale *= self.params.gyro_gain_scale                                    # the preset's tuning
        if self.params.gyro_stiff_share:                                        # stiff servos: less of it
            scale *= max(self.calibration.estimate, 1.0) ** -self.params.gyro_stiff_share
        hip_roll, knee, ankle_pitch, ankle_roll = (g * scale for g in self.feedback.gyro)
        roll_rate, pitch_rate = float(gyro[0]), float(gyro[1])
        natural = [0.0, hip_roll * roll_rate, 0.0, knee * pitch_rate, ankle_pitch * pitch_rate, ankle_roll * roll_rate]
        out = np.zeros(len(self._names))
        out[self._both_legs] = np.array(natural * len(self.legs)) * self._both_signs      # every leg at once
        return out
