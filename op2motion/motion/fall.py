"""Falls: :class:`Supervisor` wraps any controller, sees it fall, lets it land softly, gets it up and walks on.

Every 8 ms the supervisor watches the IMU (an attitude filter of the gyro and the accelerometer, as the walk's, and
the ROBOTIS framework's averaged fore-aft test on the board's counts, :class:`op2motion.robot.imu.FallWatch`, the
robot's own) and, while the robot is up, passes the tick on to the
controller it wraps. When the robot is down (the torso past :data:`~.lying.FALL_TILT_DEG`, or the framework's test
with the torso past :data:`FRAMEWORK_GUARD_DEG`):

1. **stop** the wrapped controller (its goals are no longer sent) and **lower the servos' torque limit** to
   :data:`FALLING_TORQUE_SHARE` (``torque_limits``, the MX-28's torque-limit register): the goals follow the joints
   where the fall puts them, so the servos neither fight the fall nor strike the floor at full torque;
2. **wait** until the body has kept still (:mod:`.stillness`; at most :data:`WAIT_MAX_S`), then restore the torque;
3. **get up** (:class:`.getup.GetUp`, or the one given);
4. **resume**: blend from where the robot stands to the wrapped controller's first goals (:func:`.planner.blend`),
   and run it again: its ``resume(joint_positions, t_s)`` hook when it offers one, with its own clock at the fall (a
   steered walk keeps its command, and its timeline goes on from where the fall stopped it: nothing commanded while it
   was down is skipped), else ``start(joint_positions)``. With ``resume=False``, or when getting up failed, it reports
   instead: :attr:`Supervisor.done`, :attr:`Supervisor.events` says what happened and when.

Its :attr:`plan` is the wrapped controller's, :data:`EXTRA_S` longer (a fall and a get-up take time). Check it in
physics with ``Setup(full_length=True)``: a run ends early once the robot has fallen, which here is where the
supervisor's work begins.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Mapping

import numpy as np

from op2motion.errors import Op2MotionError
from op2motion.motion.getup import GetUp
from op2motion.motion.lying import FALL_TILT_DEG
from op2motion.motion.stillness import Stillness
from op2motion.physics import Controller, ControllerHooks, Plan, hooks_of
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.imu import FallWatch, board_of, encode_imu
from op2motion.robot.spec import GRAVITY_M_S2, Spec

FALLING_TORQUE_SHARE = 0.3      # the servos' torque limit while the robot falls and lies
WAIT_MAX_S = 3.0                # the longest wait for the body to keep still after a fall [s]
RESUME_LEAST_S = 1.0            # the blend back to the wrapped controller takes at least this [s]
ATTITUDE_TAU_S = 0.5            # the attitude filter's time constant [s] (as the walk's)
ACCEL_TAU_S = 0.1               # the accelerometer's low-pass before its tilt is taken [s]
EXTRA_S = 30.0                  # the plan's extra length for a fall, a wait and a get-up [s]
FRAMEWORK_GUARD_DEG = 20.0      # the framework's accelerometer test counts only with the torso this far tilted too:
                                # a push alone (30 N forward: +10 m/s² for 0.1 s) moves its average past its limits
MIN_GRAVITY_SHARE = 0.5         # an accelerometer reading below this share of g says nothing about the tilt


class Attitude:
    """Pitch and roll [rad] from the gyro integrated and, slowly, the accelerometer's gravity (low-passed first)."""

    def __init__(self) -> None:
        self.angles: np.ndarray | None = None
        self.accel: np.ndarray | None = None

    def update(self, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray) -> None:
        """One tick's gyro (3,) [rad/s] and accelerometer (3,) [m/s²] (torso frame). Until the accelerometer first
        reads :data:`MIN_GRAVITY_SHARE` of gravity (a physics check ramps gravity in) nothing is estimated; after,
        such readings (free fall) leave the estimate to the gyro."""
        a = np.asarray(accel_m_s2, dtype=float)
        dt = CONTROL_PERIOD_S
        rates = np.array([gyro_rad_s[1], gyro_rad_s[0]], dtype=float)
        if np.linalg.norm(a) < MIN_GRAVITY_SHARE * GRAVITY_M_S2:
            if self.angles is not None:
                self.angles = self.angles + rates * dt
            return
        self.accel = a.copy() if self.accel is None else self.accel + dt / (ACCEL_TAU_S + dt) * (a - self.accel)
        g = self.accel
        measured = np.array([math.atan2(-g[0], g[2]), math.atan2(g[1], math.hypot(g[0], g[2]))])
        blend = dt / (ATTITUDE_TAU_S + dt)
        self.angles = measured if self.angles is None else (1.0 - blend) * (self.angles + rates * dt) + (
            blend * measured)

    @property
    def tilt_deg(self) -> float:
        """The torso's tilt from upright [deg]."""
        if self.angles is None:
            return 0.0
        pitch, roll = self.angles
        return math.degrees(math.acos(max(-1.0, min(1.0, math.cos(pitch) * math.cos(roll)))))


class Supervisor(ControllerHooks):
    """Wraps a controller: fall, land, wait, get up, resume (see the module docstring); its hooks are the wrapped
    controller's while that runs."""

    handles_falls = True        # on the robot, the bus's safety watch leaves falls to it (op2motion.bus.loop)

    def __init__(self, controller: Controller[Plan], getup: GetUp | None = None, spec: Spec | None = None,
                 resume: bool = True, extra_s: float = EXTRA_S):
        self.inner, self.hooks, self.resumes = controller, hooks_of(controller), resume
        self.stops_itself = self.hooks.stops_itself
        self.getup = getup or GetUp(spec)
        self.spec = self.getup.spec
        plan: Plan = controller.plan
        self.plan = replace(plan, duration_s=plan.duration_s + extra_s)
        self._reset()

    def _reset(self) -> None:
        self.phase, self.since, self.offset = "run", 0.0, 0.0
        self.attitude, self.stillness = Attitude(), Stillness()
        self.board = board_of(self.spec)
        self.fall_watch = FallWatch(self.board)
        self.fallen: str | None = None
        self.hold = np.zeros(len(self.spec.joints))
        self.rows: np.ndarray | None = None
        self.row = 0
        self.events: list[tuple[float, str]] = []
        self.falls = 0
        self.paused_at = self.fell_at = 0.0            # the wrapped controller's clock, and ours, at the last fall
        self.paused: str | None = None                 # what resuming says of the wrapped controller's commands

    @property
    def p_gains(self) -> Mapping[str, float] | None:
        """The P gains of whoever drives the servos (GetUp's while getting up)."""
        if self.phase == "getting_up":
            return self.getup.p_gains
        return self.hooks.p_gains if self.phase == "run" else None

    @property
    def torque_limits(self) -> Mapping[str, float] | None:
        """Lowered while the robot falls and lies; the wrapped controller's otherwise."""
        if self.phase == "falling":
            return {n: FALLING_TORQUE_SHARE for n in self.spec.joint_names}
        return self.hooks.torque_limits if self.phase == "run" else None

    @property
    def done(self) -> bool:
        """The wrapped controller is done (after any falls), or the robot could not get up, or it got up and was
        not to resume."""
        return self.phase in ("gave_up", "up") or (self.phase == "run" and self.inner.done)

    def stop(self) -> None:
        """Pass a stop request on to the wrapped controller (one that stops itself, a steered walk); down or getting
        up, it goes on to the stop once it runs again."""
        self.hooks.stop()

    def start(self, joint_positions: Mapping[str, float]) -> Mapping[str, float]:
        """Start over, and the wrapped controller with it."""
        self._reset()
        return self.inner.start(joint_positions)

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> Mapping[str, float]:
        """The goals at ``t_s`` [s] (see the module docstring)."""
        joints = np.array([joint_positions[n] for n in self.spec.joint_names])
        self.attitude.update(gyro_rad_s, accel_m_s2)
        self.stillness.update(np.asarray(gyro_rad_s, dtype=float), joints)
        if self.attitude.angles is not None:
            self.fallen = self.fall_watch.add(encode_imu(self.board, np.asarray(gyro_rad_s, dtype=float),
                                                     np.asarray(accel_m_s2, dtype=float)))
        if self.phase == "run":
            armed = self.attitude.angles is not None
            tilt = self.attitude.tilt_deg
            down = armed and (tilt > FALL_TILT_DEG or (tilt > FRAMEWORK_GUARD_DEG and self.fallen is not None))
            if not down:
                return self.inner.step(t_s - self.offset, gyro_rad_s, accel_m_s2, joint_positions)
            self.falls += 1
            self.paused_at, self.fell_at = t_s - self.offset, t_s
            self.events.append((t_s, f"fall detected (tilt {self.attitude.tilt_deg:.0f}°)"))
            self.phase, self.since, self.stillness = "falling", t_s, Stillness()
        if self.phase == "falling":
            self.hold = joints
            if self.stillness.still or t_s - self.since >= WAIT_MAX_S:
                self.events.append((t_s, "still; getting up"))
                self.phase, self.since = "getting_up", t_s
                return self.getup.start(joint_positions)
            return dict(zip(self.spec.joint_names, joints.tolist()))
        if self.phase == "getting_up":
            goals = self.getup.step(t_s - self.since, gyro_rad_s, accel_m_s2, joint_positions)
            if self.getup.done:
                self._got_up(t_s, joint_positions, joints)
            return goals
        if self.phase == "blend":
            if self.rows is None:
                raise Op2MotionError("the supervisor blends to rows it has not planned")
            self.hold = self.rows[self.row]
            self.row += 1
            if self.row >= len(self.rows):
                self.phase, self.offset = "run", t_s
                self.events.append((t_s, "resumed"))
                if self.paused:
                    self.events.append((t_s, self.paused))
        return dict(zip(self.spec.joint_names, self.hold.tolist()))

    def _got_up(self, t_s: float, joint_positions: Mapping[str, float], joints: np.ndarray) -> None:
        """GetUp is done: blend back to the wrapped controller, or report."""
        if not self.getup.stood:
            self.phase = "gave_up"
            self.events.append((t_s, "could not get up"))
            return
        self.events.append((t_s, "standing again"))
        if not self.resumes:
            self.phase = "up"
            return
        from op2motion.motion.planner import blend

        first = self.hooks.resume(joint_positions, self.paused_at)
        down_s = t_s - self.fell_at
        self.paused = None if first is None else (f"its commands were paused while it was down ({down_s:.1f} s): "
                                                  f"they go on from where the fall stopped them")
        first = self.inner.start(joint_positions) if first is None else first
        target = np.array([first.get(n, joints[i]) for i, n in enumerate(self.spec.joint_names)])
        self.rows, self.row, self.hold = blend(joints, target, self.spec, RESUME_LEAST_S), 0, joints
        self.phase = "blend"
