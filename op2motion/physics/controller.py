"""Who tells the servos what to do: the :class:`Controller` protocol, the hooks a controller may offer
(:class:`ControllerHooks`), the goal merger both loops use (:class:`GoalMerger`), and the open-loop :class:`Schedule`.

The physics loop (:mod:`.loop`) and the robot's 8 ms loop (:mod:`op2motion.bus.loop`) call a controller every
:data:`~op2motion.robot.framework.CONTROL_PERIOD_S` (8 ms, the robot's motion timer) with what the OP2's CM-730 board
measures:

* ``start(joint_positions)`` once, where the run begins (it also resets the controller, so one controller serves
  several runs one after the other); it returns the first goals;
* ``step(t_s, gyro_rad_s, accel_m_s2, joint_positions)`` at every later tick: the time since the start [s], the
  torso's angular velocity [rad/s] and its accelerometer reading (specific force: the acceleration less gravity,
  +9.81 m/s² upwards at rest) [m/s²], both in the torso frame (x forward, y left, z up), and the joint angles;
  it returns the goals;
* ``done``: true once it has nothing more to send (the servos then hold its last goals).

Positions and goals are ``{official joint name: rad}``; a goal left out keeps its previous value, an unknown name is
refused. A controller carries the :class:`~.plan.Plan` it follows (``plan``): where the robot starts, the P gains, and
what the judge compares the run with (the planned supports and torso). Anything more it offers, it declares as
:class:`ControllerHooks`.

:class:`Schedule` is the open-loop controller: it ignores its sensors and sends the plan's goals row by row. A held
pose, a planned motion, a played action page and a planned gait are each a schedule.
"""

from __future__ import annotations

from typing import Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from op2motion.errors import InputError
from op2motion.physics.plan import DEFAULT_SECONDS, Plan
from op2motion.robot.framework import CONTROL_PERIOD_S
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, SupportName

Goals = Mapping[str, float]


@runtime_checkable
class Controller(Protocol):
    """Turns the robot's sensors into servo goals every 8 ms (see the module docstring)."""

    plan: Plan

    def start(self, joint_positions: Goals) -> Goals:
        """Reset, and the first goals {joint: rad} for a robot standing at ``joint_positions`` {joint: rad}."""

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray, joint_positions: Goals) -> Goals:
        """The goals {joint: rad} at ``t_s`` [s] after the start, given the torso's gyro (3,) [rad/s] and
        accelerometer (3,) [m/s²] (torso frame) and the joint angles {joint: rad}."""

    @property
    def done(self) -> bool:
        """Nothing more to send: the servos hold the last goals."""


class ControllerHooks:
    """What a controller may offer beyond ``plan``, ``start``, ``step`` and ``done``, and what both loops do when it
    does not (the defaults). A controller offers a hook by subclassing this and overriding it (a property, or a class
    attribute that instances may then set); one that does not subclass it offers none (:func:`hooks_of`).

    * ``p_gains``: {joint: P} over the plan's P gains while set (joints left out keep the plan's); None: the plan's;
    * ``torque_limits``: {joint: share of the servo's torque, 0 to 1} while set (the MX-28's torque-limit register,
      e.g. while the robot falls; joints left out keep all of it); None: full torque;
    * ``takes_foot_forces``: ``step`` also takes ``foot_forces_n``, each sole's vertical load [N] ({"left": ..,
      "right": ..}), measured in physics; the robot's loop refuses such a controller (the OP2 does not measure them);
    * ``stops_itself``: a stop request (Ctrl-C on the robot) calls :meth:`stop` and the loop runs on until ``done``
      (at most :data:`op2motion.bus.stopping.SOFT_STOP_MAX_S`); otherwise the loop freezes the goals;
    * ``resume(joint_positions, t_s)``: the goals to go on with, the robot put back on its feet (after a fall, at
      ``t_s`` [s] of the fall supervisor's clock); None: the supervisor calls ``start`` instead;
    * ``handles_falls``: the robot's safety watch does not stop the run for a fall (the fall supervisor's own).
    """

    handles_falls = takes_foot_forces = stops_itself = False

    @property
    def p_gains(self) -> Mapping[str, float] | None:
        """None: the plan's P gains."""
        return None

    @property
    def torque_limits(self) -> Mapping[str, float] | None:
        """None: full torque."""
        return None

    def stop(self) -> None:
        """Nothing: a controller that does not stop itself is stopped by its loop."""

    def resume(self, joint_positions: Goals, t_s: float) -> Goals | None:
        """None: nothing to go on with."""
        return None


NO_HOOKS = ControllerHooks()


def hooks_of(controller: object) -> ControllerHooks:
    """The hooks ``controller`` offers: itself if it subclasses :class:`ControllerHooks`, else :data:`NO_HOOKS`."""
    return controller if isinstance(controller, ControllerHooks) else NO_HOOKS


class GoalMerger:
    """A controller's output as both loops take it: named goals into the (20,) the servos hold, and the P gains and
    torque-limit shares its hooks set over the plan's."""

    def __init__(self, controller: Controller, joint_names: Sequence[str]):
        self.controller, self.hooks, self.names = controller, hooks_of(controller), tuple(joint_names)
        self.index = {n: i for i, n in enumerate(self.names)}

    def merge(self, held: np.ndarray, goals: Goals) -> None:
        """``goals`` {joint: rad} into ``held`` (20,) [rad], in place; an unknown joint name is refused."""
        for name, value in goals.items():
            if name not in self.index:
                raise InputError(f"expected goals by official joint name ({self.names[0]}, ...), got {name!r}",
                                 "goals")
            held[self.index[name]] = float(value)

    def p_gains(self, row: int) -> np.ndarray:
        """The P gains (20,) at plan row ``row``: the plan's, the ``p_gains`` hook's over them."""
        over = self.hooks.p_gains
        planned = self.controller.plan.p_gains[row]
        if not over:
            return planned.copy()                  # (the plan's, as they were: nothing to merge every 8 ms)
        return np.array([over.get(n, p) for n, p in zip(self.names, planned)], dtype=float)

    def torque_shares(self) -> np.ndarray | None:
        """The ``torque_limits`` hook as shares (20,) of the servos' torque, 0 to 1; None while it sets none."""
        limits = self.hooks.torque_limits
        return np.clip([float(limits.get(n, 1.0)) for n in self.names], 0.0, 1.0) if limits else None


def check_goals(goals: np.ndarray, spec: Spec, param: str = "goals") -> np.ndarray:
    """Goals as rows (K, 20) [rad] in the spec's joint order, finite."""
    goals = np.asarray(goals, dtype=float)
    if goals.ndim == 1:
        goals = goals[None]
    if goals.ndim != 2 or goals.shape[1] != len(spec.joints) or not np.all(np.isfinite(goals)):
        raise InputError(f"expected finite goals of shape (K, {len(spec.joints)}), got {goals.shape}", param)
    return goals


class Schedule:
    """The open-loop controller: the plan's goals, row by row (:meth:`.plan.Plan.row`), sensors ignored."""

    def __init__(self, plan: Plan, joint_names: Sequence[str]):
        if plan.goals.shape[1] != len(joint_names):
            raise InputError(f"expected goals for {len(joint_names)} joints, got {plan.goals.shape[1]}", "goals")
        self.plan = plan
        self.joint_names = tuple(joint_names)
        self._t = 0.0

    @classmethod
    def hold(cls, servo: np.ndarray, support: Support | SupportName, spec: Spec, seconds: float = DEFAULT_SECONDS,
             p_gains: np.ndarray | None = None) -> "Schedule":
        """One pose, servo angles (20,) [rad] in the spec's joint order, held on ``support`` for ``seconds``; the
        servos' P gains (20,) default to the spec's."""
        servo = check_goals(servo, spec, "servo angles")[0]
        gains = np.full(len(spec.joints), spec.servo.p_gain_default) if p_gains is None else p_gains
        return cls(Plan.hold(servo, support, seconds, gains), spec.joint_names)

    @classmethod
    def motion(cls, goals: np.ndarray, p_gains: np.ndarray, supports: Sequence[Support | SupportName], spec: Spec,
               dt: float = CONTROL_PERIOD_S) -> "Schedule":
        """A motion: goals (K, 20) [rad] every ``dt`` [s] with the P gains (K, 20) they were sent with, each row on
        its support (see :meth:`.plan.Plan.motion`)."""
        goals = check_goals(goals, spec)
        return cls(Plan.motion(goals, p_gains, tuple(supports), dt), spec.joint_names)

    def goals_at(self, t_s: float) -> np.ndarray:
        """The goals (20,) [rad] the schedule sends at ``t_s`` [s]."""
        return self.plan.goals[self.plan.row(t_s)]

    def _named(self, row: np.ndarray) -> dict[str, float]:
        return dict(zip(self.joint_names, row.tolist()))

    def start(self, joint_positions: Goals) -> Goals:
        """Row 0's goals."""
        self._t = 0.0
        return self._named(self.plan.goals[0])

    def step(self, t_s: float, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray, joint_positions: Goals) -> Goals:
        """The row of ``t_s``'s goals (the sensors are ignored)."""
        self._t = t_s
        return self._named(self.goals_at(t_s))

    @property
    def done(self) -> bool:
        """The last row has been sent."""
        return self._t >= self.plan.end_s
