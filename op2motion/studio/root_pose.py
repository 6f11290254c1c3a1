"""Where the studio draws the robot: the torso (the URDF's root) placed so that the stance sole lies on the floor at
the origin (X forward, Y left, Z up), from the spec's joint table."""

from __future__ import annotations

import numpy as np

from op2motion.kinematics.frames import quat_xyzw
from op2motion.kinematics.tree import link_frames
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side


def wxyz(rot: np.ndarray) -> tuple[float, float, float, float]:
    """A rotation matrix (3, 3) as viser's quaternion (w, x, y, z)."""
    x, y, z, w = quat_xyzw(rot)
    return w, x, y, z


def root_in_sole(spec: Spec, servo: np.ndarray, stance: Side) -> tuple[np.ndarray, np.ndarray]:
    """The torso (URDF root) frame in the stance sole frame: rotation (3, 3) and origin (3,) [m]."""
    rot, origin = link_frames(spec, servo)[spec.joint(f"{stance[0]}_ank_roll").child]
    sole = origin + rot @ np.array([0.0, 0.0, -spec.foot.sole_below_ankle])
    return rot.T, -rot.T @ sole
