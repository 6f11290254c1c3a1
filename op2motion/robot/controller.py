"""The controller contract: what the robot's motion timer calls every 8 ms, and what both loops that call it (the
physics loop, :mod:`op2motion.physics.loop`, and the robot's, :mod:`op2motion.bus.loop`) take from it.

The loops call a controller every :data:`~op2motion.robot.framework.CONTROL_PERIOD_S` (8 ms, the robot's motion timer)
with what the OP2's CM-730 board measures:

* ``start(joint_positions)`` once, where the run begins (it also resets the controller, so one controller serves
  several runs one after the other); it returns the first goals;
* ``step(t_s, gyro_rad_s, accel_m_s2, joint_positions)`` at every later tick: the time since the start [s], the
  torso's angular velocity [rad/s] and its accelerometer reading (specific force: the acceleration less gravity,
  +9.81 m/s² upwards at rest) [m/s²], both in the torso frame (x forward, y left, z up), and the joint angles;
  it returns the goals;
* ``done``: true once it has nothing more to send (the servos then hold its last goals).

Positions and goals are ``{official joint name: rad}``; a goal left out keeps its previous value, an unknown name is
refused. A controller carries the plan it follows (``plan``, a :class:`RunPlan`: in practice an
:class:`op2motion.physics.Plan`): where the robot starts, the P gains, its rows' supports. Anything more it offers, it
declares as :class:`ControllerHooks`; :class:`GoalMerger` turns its output into what the servos hold.

This module sits below the physics (the robot's transport and its loop use it without the physics engines).
"""

from __future__ import annotations

from typing import Any, Mapping, Protocol, Sequence, TypeVar, runtime_checkable

import numpy as np

from op2motion.errors import InputError


class RunPlan(Protocol):
    """What a loop reads of a controller's plan (:class:`op2motion.physics.Plan` has it all)."""

    @property
    def goals(self) -> np.ndarray:
        """The goal rows (K, 20) [rad]."""

    @property
    def p_gains(self) -> np.ndarray:
        """Each row's P gains (K, 20)."""

    @property
    def duration_s(self) -> float:
        """How long a run of it lasts [s]."""

    @property
    def tick_phase_s(self) -> float:
        """When the first control tick after the start falls [s]."""

    @property
    def contact(self) -> Any:
        """The rows' own planned contacts, or None for a plan without them."""

    @property
    def contacts(self) -> Sequence[Any]:
        """Each row's planned contact (the supports where the plan has no contact of its own)."""

    def row(self, t_s: float) -> int:
        """The row played at ``t_s`` [s]."""


Goals = Mapping[str, float]
#: The plan type a controller carries: a loop that needs more of it than :class:`RunPlan` (the physics loop: the
#: planned torso and supports) asks for ``Controller[Plan]``.
PlanT = TypeVar("PlanT", bound=RunPlan, covariant=True)


@runtime_checkable
class Controller(Protocol[PlanT]):
    """Turns the robot's sensors into servo goals every 8 ms (see the module docstring)."""

    @property
    def plan(self) -> PlanT:
        """The plan it follows."""

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

    def __init__(self, controller: Controller[RunPlan], joint_names: Sequence[str]):
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
        planned: np.ndarray = self.controller.plan.p_gains[row]
        if not over:
            return planned.copy()                  # (the plan's, as they were: nothing to merge every 8 ms)
        return np.array([over.get(n, p) for n, p in zip(self.names, planned)], dtype=float)

    def torque_shares(self) -> np.ndarray | None:
        """The ``torque_limits`` hook as shares (20,) of the servos' torque, 0 to 1; None while it sets none."""
        limits = self.hooks.torque_limits
        return np.clip([float(limits.get(n, 1.0)) for n in self.names], 0.0, 1.0) if limits else None
