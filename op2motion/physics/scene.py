"""The scene every engine builds: the floor, the time step, and how contacts are reported.

The floor is a plane with Coulomb friction :data:`FLOOR_FRICTION` against every link (a robot foot on a
competition carpet or a lab floor: the walking literature and ROBOTIS-OP3-Common#11 use about 0.8). Each engine
steps at :data:`TIME_STEP_S` (1 kHz) in torque control.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

FLOOR_FRICTION = 0.8
TIME_STEP_S = 0.001
BALL_NAME = "ball"          # the ball's body (:mod:`.ball`), apart from the robot's links
#: A physics engine that judges a run.
EngineName = Literal["pybullet", "mujoco"]
ENGINES: tuple[EngineName, ...] = get_args(EngineName)


@dataclass(frozen=True)
class Contact:
    """A contact of ``link`` with the floor (``other`` None) or with another link: normal force [N], total force
    on ``link`` [N] and the contact point [m], world frame."""

    link: str
    other: str | None
    normal_force: float
    force: np.ndarray
    point: np.ndarray
