"""The engines' common face: the :class:`Engine` protocol, and how to make one.

Each engine builds the scene of :mod:`.scene` (the floor, 1 kHz) and steps it in torque control; the servo model
(:mod:`op2motion.model.servo`) supplies the torques, the engine integrates its losses (damping, friction, rotor
inertia where it can). An engine reports only the torso (``body_link``) pose and velocity, the 20 joint angles and
velocities, and the contacts: :mod:`.body` turns them into everything the judge measures, the same way for every
engine.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from op2motion.errors import InputError
from op2motion.model.servo import ServoModel
from op2motion.physics.ball import Ball
from op2motion.physics.scene import ENGINES, FLOOR_FRICTION, TIME_STEP_S, Contact, EngineName
from op2motion.robot.spec import Spec

__all__ = ["ENGINES", "TIME_STEP_S", "Contact", "Engine", "make_engine", "snapshot_png"]


class Engine(Protocol):
    """One world with the floor and the robot, torque-controlled, stepped at :attr:`time_step` [s]."""

    name: str
    time_step: float

    def reset(self, base_pos: np.ndarray, base_rot: np.ndarray, q: np.ndarray) -> None:
        """Teleport: torso link frame at (``base_pos`` [m], ``base_rot`` (3, 3)), joints at ``q`` [rad], at rest."""

    def set_gravity(self, scale: float) -> None:
        """Gravity at ``scale`` of its full strength."""

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles and velocities (20,) [rad, rad/s] in the spec's joint order."""

    def step(self, torque: np.ndarray, push: np.ndarray | None = None) -> None:
        """One time step with the servos' active ``torque`` (20,) [N·m] and an optional ``push`` (3,) [N, world]
        at the torso's centre of mass."""

    def base(self) -> tuple[np.ndarray, np.ndarray]:
        """Torso link frame: position [m] and rotation (3, 3), world frame."""

    def base_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """Velocity of the torso link frame's origin: linear [m/s] and angular [rad/s], both in the world frame."""

    def contacts(self) -> list[Contact]:
        """Contacts of the robot with the floor (``other`` None) and with itself (never the ball's)."""

    def ball_state(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The ball's centre (3,) [m] and velocity (3,) [m/s], world frame (None: the world has no ball)."""

    def close(self) -> None:
        """Release the world."""


def make_engine(name: EngineName, spec: Spec, servo: ServoModel, friction: float = FLOOR_FRICTION,
                ball: Ball | None = None) -> Engine:
    """A fresh world of engine ``name`` (one of :data:`ENGINES`) with the robot, a floor of Coulomb ``friction``
    and the ``ball`` (None: none)."""
    if name == "pybullet":
        from op2motion.physics.pybullet_engine import PyBulletEngine

        return PyBulletEngine(spec, servo, TIME_STEP_S, friction=friction, ball=ball)
    if name == "mujoco":
        from op2motion.physics.mujoco_engine import MuJoCoEngine

        return MuJoCoEngine(spec, servo, TIME_STEP_S, friction, ball)
    raise InputError(f"expected one of {', '.join(ENGINES)}, got {name!r}", "engine")


def snapshot_png(engine: Engine, spec: Spec, servo: ServoModel) -> bytes:
    """A TinyRenderer picture of the engine's current state (PyBullet renders for both engines: MuJoCo's renderer
    needs an OpenGL context)."""
    from op2motion.physics.pybullet_engine import PyBulletEngine

    if isinstance(engine, PyBulletEngine):
        return engine.snapshot()
    q, _ = engine.state()
    pos, rot = engine.base()
    painter = PyBulletEngine(spec, servo, TIME_STEP_S)
    try:
        painter.reset(pos, rot, q)
        return painter.snapshot()
    finally:
        painter.close()
