"""The official ROBOTIS joint table walked as a tree, one pose at a time: every link's frame in the torso frame.

Each joint turns its child link about its axis after the joint's fixed origin (xyz, then roll-pitch-yaw), as in the
URDF. This is the description's own kinematics, independent of the book's D-H chain; the D-H model uses it once
per spec to find where each link's centre of mass sits in its D-H frames (:mod:`.com`), and the tests use it as an
oracle for the D-H model.
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.robot.spec import Spec, rpy_matrix


def axis_rotation(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    """Rotation by ``angle`` [rad] about a unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=float)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    rotation: np.ndarray = np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k
    return rotation


def link_frames(spec: Spec, servo: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{link: (rotation (3, 3), origin (3,) [m])}`` in the torso (root link) frame for servo angles (20,) [rad]."""
    angle = dict(zip(spec.joint_names, np.asarray(servo, dtype=float)))
    frames = {spec.root_link: (np.eye(3), np.zeros(3))}
    pending = list(spec.joints)
    while pending:
        for joint in [j for j in pending if j.parent in frames]:
            rp, pp = frames[joint.parent]
            origin = pp + rp @ np.asarray(joint.origin_xyz)
            frames[joint.child] = (rp @ rpy_matrix(joint.origin_rpy) @ axis_rotation(joint.axis, angle[joint.name]),
                                   origin)
            pending.remove(joint)
    return frames
