"""The robot following a pose someone edits (the pose studio's "follow on the robot"): a :class:`Follower` runs the
8 ms loop (:func:`~.loop.run_controller`, with its safety watch) in a thread of its own; :meth:`Follower.set_target`
gives it the pose to reach, and each goal moves towards it at most :data:`FOLLOW_SPEED_RAD_S` per second, so a
slider dragged across its range moves the robot at a walking pace, never at the servo's full speed.
:meth:`Follower.pose` reads where the robot's joints are (the studio's "read the pose from the robot").

The studio calls it from its own threads; a target is one array swapped in whole, so no lock is needed::

    follower = Follower("/dev/ttyUSB0", spec)
    follower.start()                          # torque on where the joints are; the loop runs
    follower.set_target(pose.servo)           # every edit
    follower.pose()                           # the robot's joint angles (20,) [rad]
    follower.close()                          # the loop stops; the servos hold the last goals
"""

from __future__ import annotations

import threading
from typing import Any, Mapping

import numpy as np

from op2motion.bus.loop import LoopReport, Tick, run_controller
from op2motion.bus.port import RobotPort
from op2motion.bus.safety import clip_goals, mechanical_bounds
from op2motion.bus.session import Session
from op2motion.errors import InputError
from op2motion.physics import Plan
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

FOLLOW_SPEED_RAD_S = 1.0           # the goals' top speed towards the target (a sixth of the MX-28's no-load speed)
FOREVER_S = float("inf")


class FollowController:
    """A :class:`~op2motion.physics.Controller` whose goals move towards a target that may change at any time, at
    most ``speed`` [rad/s] per joint."""

    def __init__(self, start: np.ndarray, spec: Spec, speed: float = FOLLOW_SPEED_RAD_S):
        self.spec, self.speed = spec, speed
        self.names = spec.joint_names
        self.lower, self.upper = mechanical_bounds(spec)
        gains = np.full((1, len(start)), float(spec.servo.p_gain_default))
        self.plan = Plan("pose", np.asarray(start, dtype=float)[None], gains, (Support.DOUBLE,), 1.0, 0.0, FOREVER_S)
        self.goals = np.asarray(start, dtype=float).copy()
        self.target = self.goals.copy()

    @property
    def done(self) -> bool:
        """Never: it follows until stopped."""
        return False

    def set_target(self, servo: np.ndarray) -> None:
        """The pose to reach (20,) [rad], clipped to the mechanical ranges."""
        self.target = clip_goals(np.asarray(servo, dtype=float), self.lower, self.upper)[0]

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """Goals where the joints are."""
        self.goals = np.array([joint_positions[n] for n in self.names])
        return dict(zip(self.names, self.goals.tolist()))

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """One 8 ms step towards the target."""
        limit = self.speed * CONTROL_PERIOD_S
        self.goals = self.goals + np.clip(self.target - self.goals, -limit, limit)
        return dict(zip(self.names, self.goals.tolist()))


class Follower:
    """The robot on ``port`` following a target pose (see the module docstring)."""

    def __init__(self, port: RobotPort, spec: Spec, speed: float = FOLLOW_SPEED_RAD_S):
        self.port, self.spec, self.speed = port, spec, speed
        self.stop = threading.Event()
        self.session: Session | None = None
        self.controller: FollowController | None = None
        self.thread: threading.Thread | None = None
        self.report: LoopReport | None = None
        self.latest: np.ndarray | None = None
        self.error: BaseException | None = None

    def start(self) -> None:
        """Open the robot (preflight: refused if unfit), torque on where the joints are, the loop in a thread."""
        self.session = Session(self.port, self.spec).__enter__()
        try:
            status = self.session.ready_for_motion()
        except BaseException:
            self.session.__exit__(None, None, None)
            raise
        self.latest = status.servo_angles
        self.controller = FollowController(status.servo_angles, self.spec, self.speed)
        self.thread = threading.Thread(target=self._run, name="op2-follow", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        if self.session is None or self.controller is None:
            raise InputError("expected start() before the follower runs", "follower")
        try:
            self.report = run_controller(self.controller, self.session.robot, duration_s=FOREVER_S, stop=self.stop,
                                         on_tick=self._seen)
        except BaseException as exc:                                   # reported by running() and close()
            self.error = exc

    def _seen(self, tick: Tick) -> None:
        self.latest = tick.positions

    def set_target(self, servo: np.ndarray) -> None:
        """The pose the robot moves to (20,) [rad]."""
        if self.controller is not None:
            self.controller.set_target(servo)

    def pose(self) -> np.ndarray | None:
        """The robot's joint angles (20,) [rad] as last read."""
        return None if self.latest is None else self.latest.copy()

    def running(self) -> bool:
        """Whether the loop still runs (a fault ends it: see :attr:`report`)."""
        return self.thread is not None and self.thread.is_alive()

    def close(self) -> Any:
        """Stop the loop (the servos hold the last goals) and release the port; the loop's report."""
        self.stop.set()
        if self.thread is not None:
            self.thread.join(timeout=5.0)
        if self.session is not None:
            self.session.__exit__(None, None, None)
            self.session = None
        if self.error is not None:
            raise self.error
        return self.report
