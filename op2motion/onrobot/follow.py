"""The robot following a pose someone edits (the pose studio's robot, ``studio --robot PORT``), under the robot's
safety contract: nothing moves unchecked, nothing jumps.

A :class:`Follower` runs the 8 ms loop (:func:`~op2motion.bus.loop.run_controller`, with its safety watch) in a thread
of its own. Opened, it holds the robot where it stands (torque on with goals where the joints are) and moves nothing
until the user asks (:meth:`Follower.move_to`). Every move to a pose is the same planned move ``robot play`` makes
(:func:`~.plans.move`: within the servos' speed, weight shifts where the support changes), checked in physics from
where the robot is (:func:`~.plans.physics_problem`) before a goal is sent; a refused move leaves the robot holding
and says why. Once a pose has been reached that way, edits that keep the target within :data:`JOG_STEP_RAD` (the
studio's largest jog step) of that checked pose are followed directly, each goal moving towards the target at most
:data:`FOLLOW_SPEED_RAD_S`; anything further is planned and checked again (so no string of small edits walks the
robot off a checked pose). Every change of state (moving, refused, following, a fault and what the robot does now)
reaches ``on_event`` in words at once.

The studio calls it from its own threads::

    follower = Follower("/dev/ttyUSB0", spec, on_event=print)
    follower.start()                          # torque on where the joints are: nothing moves
    follower.move_to(pose)                    # planned, checked in physics, then played; then it follows
    follower.request(pose)                    # every edit: followed, or planned and checked again
    follower.pose()                           # the robot's joint angles (20,) [rad]
    follower.close()                          # the loop stops; the servos hold the last goals
"""

from __future__ import annotations

import math
import threading
from typing import Any, Callable, Mapping

import numpy as np

from op2motion.bus.loop import LoopReport, Tick, run_controller
from op2motion.bus.port import RobotPort
from op2motion.bus.safety import after_fault, clip_goals, mechanical_bounds
from op2motion.bus.session import Session
from op2motion.errors import InputError, Op2MotionError
from op2motion.physics import Plan
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support

FOLLOW_SPEED_RAD_S = 1.0           # the goals' top speed towards a followed target (a sixth of the MX-28's no-load)
JOG_STEP_RAD = math.radians(5.0)   # followed without a new check: within this of the last physics-checked pose
ROUNDING_RAD = 1e-9                # a jog of exactly 5° is within it whatever the degrees' rounding
FOREVER_S = float("inf")
Event = Callable[[str], None]


class FollowController:
    """A :class:`~op2motion.physics.Controller` that holds, plays a checked trajectory (:meth:`play`), or moves
    towards a target that may change at any time, at most ``speed`` [rad/s] per joint."""

    def __init__(self, start: np.ndarray, spec: Spec, speed: float = FOLLOW_SPEED_RAD_S):
        self.spec, self.speed = spec, speed
        self.names = spec.joint_names
        self.lower, self.upper = mechanical_bounds(spec)
        gains = np.full((1, len(start)), float(spec.servo.p_gain_default))
        self.plan = Plan("pose", np.asarray(start, dtype=float)[None], gains, (Support.DOUBLE,), 1.0, 0.0, FOREVER_S)
        self.goals = np.asarray(start, dtype=float).copy()
        self.target = self.goals.copy()
        self.script: np.ndarray | None = None          # a checked trajectory's rows (K, 20) [rad], played in turn
        self.row = 0

    @property
    def done(self) -> bool:
        """Never: it follows until stopped."""
        return False

    @property
    def playing(self) -> bool:
        """Whether a checked trajectory is being played."""
        return self.script is not None

    def set_target(self, servo: np.ndarray) -> None:
        """The pose to move towards (20,) [rad], clipped to the mechanical ranges."""
        self.target = clip_goals(np.asarray(servo, dtype=float), self.lower, self.upper)[0]

    def play(self, goals: np.ndarray) -> None:
        """Play ``goals`` (K, 20) [rad], one row a tick, from the next tick; the target becomes the last row."""
        rows = np.asarray(goals, dtype=float)
        self.target = clip_goals(rows[-1], self.lower, self.upper)[0]
        self.row, self.script = 0, rows

    def start(self, joint_positions: Mapping[str, float]) -> dict[str, float]:
        """Goals where the joints are."""
        self.goals = np.array([joint_positions[n] for n in self.names])
        self.target = self.goals.copy()
        return dict(zip(self.names, self.goals.tolist()))

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray,
             joint_positions: Mapping[str, float]) -> dict[str, float]:
        """One 8 ms step: the script's next row, or towards the target."""
        script = self.script
        if script is not None:
            self.goals = script[min(self.row, len(script) - 1)].copy()
            self.row += 1
            if self.row >= len(script):
                self.script = None
        else:
            limit = self.speed * CONTROL_PERIOD_S
            self.goals = self.goals + np.clip(self.target - self.goals, -limit, limit)
        return dict(zip(self.names, self.goals.tolist()))


class Follower:
    """The robot on ``port`` holding, moving to and following poses (see the module docstring); ``on_event`` hears
    each change of state in words."""

    def __init__(self, port: RobotPort, spec: Spec, speed: float = FOLLOW_SPEED_RAD_S,
                 on_event: Event | None = None):
        self.port, self.spec, self.speed = port, spec, speed
        self.on_event: Event = on_event or (lambda text: None)
        self.stop = threading.Event()
        self.session: Session | None = None
        self.controller: FollowController | None = None
        self.thread: threading.Thread | None = None
        self.report: LoopReport | None = None
        self.latest: np.ndarray | None = None
        self.error: BaseException | None = None
        self.state = "not started"
        self.checked_pose: np.ndarray | None = None    # the last pose a physics-checked move took the robot to
        self.support = Support.DOUBLE                  # what the robot stands on (the last checked pose's)
        self.wanted: Pose | None = None                # the latest pose asked for
        self.planner: threading.Thread | None = None
        self._lock = threading.Lock()

    def _say(self, state: str) -> None:
        self.state = state
        self.on_event(state)

    def start(self) -> None:
        """Open the robot (preflight: refused if unfit), torque on where the joints are, the loop in a thread:
        nothing moves."""
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
        self._say(f"robot on {self.session.path}: holding where it stands; nothing moves until you ask "
                  f"(move the robot to the pose)")

    def _run(self) -> None:
        if self.session is None or self.controller is None:
            raise InputError("expected start() before the follower runs", "follower")
        try:
            self.report = run_controller(self.controller, self.session.robot, duration_s=FOREVER_S, stop=self.stop,
                                         on_tick=self._seen)
        except BaseException as exc:                                   # reported by running() and close()
            self.error = exc
            self._say(f"robot stopped: {exc}")
            return
        if self.report.fault is not None:
            self._say(f"robot stopped: {self.report.fault.describe()}; {after_fault(self.report.fault)}")

    def _seen(self, tick: Tick) -> None:
        self.latest = tick.positions

    def move_to(self, pose: Pose) -> None:
        """Move the robot to ``pose`` by a planned move checked in physics (in a thread: :attr:`state` and
        ``on_event`` say how it went); from then on edits are followed (:meth:`request`)."""
        self.wanted = pose
        self._plan()

    def request(self, pose: Pose) -> None:
        """An edit: followed if it keeps the target within :data:`JOG_STEP_RAD` of the last checked pose, else a
        planned, checked move; nothing before :meth:`move_to`."""
        if self.checked_pose is None or self.controller is None:
            return
        self.wanted = pose
        with self._lock:
            busy = self.planner is not None and self.planner.is_alive()
        if busy or self.controller.playing:
            return                                     # the move under way looks at the latest pose when it ends
        if self._near_checked(pose):
            self.controller.set_target(pose.servo)
            if self.state != "following the pose":
                self._say("following the pose")
        else:
            self._plan()

    def _near_checked(self, pose: Pose) -> bool:
        return (self.checked_pose is not None and pose.support is self.support
                and float(np.max(np.abs(pose.servo - self.checked_pose))) <= JOG_STEP_RAD + ROUNDING_RAD)

    def _plan(self) -> None:
        with self._lock:
            if self.planner is not None and self.planner.is_alive():
                return
            self.planner = threading.Thread(target=self._plan_and_play, name="op2-follow-plan", daemon=True)
            self.planner.start()

    def _plan_and_play(self) -> None:
        """Plan the move from where the robot is to the latest pose asked for, check it, play it; again if the
        pose changed meanwhile by more than a jog step."""
        from op2motion.onrobot.plans import CHECK_ENGINE, move, physics_problem

        while self.wanted is not None and self.controller is not None and self.running():
            pose, here = self.wanted, self.pose()
            if here is None:
                return
            self._say(f"checking the move to the pose in physics ({CHECK_ENGINE}, the servo model): the robot "
                      f"holds meanwhile")
            try:
                trajectory = move(here, pose, self.spec, self.support)
                problem = physics_problem(trajectory, self.spec)
            except Op2MotionError as exc:
                problem = str(exc)
            if problem:
                self._say(f"refused: the move to the pose {problem} in physics ({CHECK_ENGINE}); the robot holds "
                          f"where it stands")
                return
            self._say(f"moving to the pose ({trajectory.duration_s:.1f} s, checked in physics)")
            self.controller.play(trajectory.goals)
            while self.controller.playing and self.running():
                self.stop.wait(CONTROL_PERIOD_S)
            if not self.running():
                return
            self.checked_pose, self.support = pose.servo.copy(), pose.support
            if self.wanted is pose or self._near_checked(self.wanted):
                self.controller.set_target(self.wanted.servo)
                self._say("following the pose")
                return

    def pose(self) -> np.ndarray | None:
        """The robot's joint angles (20,) [rad] as last read."""
        return None if self.latest is None else self.latest.copy()

    def running(self) -> bool:
        """Whether the loop still runs (a fault ends it: see :attr:`report` and :attr:`state`)."""
        return self.thread is not None and self.thread.is_alive()

    def close(self) -> Any:
        """Stop the loop (the servos hold the last goals) and release the port; the loop's report."""
        self.stop.set()
        if self.thread is not None:
            self.thread.join(timeout=5.0)
        if self.planner is not None:
            self.planner.join(timeout=5.0)
        if self.session is not None:
            self.session.__exit__(None, None, None)
            self.session = None
        if self.error is not None:
            raise self.error
        return self.report
