"""op2motion: whole-body motion generation for the ROBOTIS OP2 humanoid, checked in physics.

The public API (imported on first use, so ``import op2motion`` does no work)::

    import op2motion as op2
    spec = op2.load_spec()                                   # the shipped OP2 spec
    pose = op2.read_pose("poses/walkready.json", spec)
    points = op2.forward(pose.book(spec), spec)              # body points, lumped CoM
    verdict = op2.validate(pose.servo, pose.support, spec)   # physics
    outcome = op2.solve(op2.PostureProblem("left", "left", (0.10, 0.05, 0.07)), spec)
"""

from __future__ import annotations

import importlib
from typing import Any

from op2motion.version import __version__

#: Public name -> (module, attribute).
_API = {
    "Op2MotionError": ("errors", "Op2MotionError"),
    "load_spec": ("robot.specfile", "load_spec"),
    "BookAngles": ("robot.joints", "BookAngles"),
    "book_to_servo": ("robot.joints", "book_to_servo"),
    "servo_to_book": ("robot.joints", "servo_to_book"),
    "Pose": ("robot.pose", "Pose"),
    "forward": ("kinematics", "forward"),
    "stability_margin": ("robot.balance", "stability_margin"),
    "solve_arm_ik": ("kinematics.arm_ik", "solve_arm_ik"),
    "PostureProblem": ("posture.cost", "PostureProblem"),
    "PSOSettings": ("posture.pso", "PSOSettings"),
    "optimize_posture": ("posture.solve", "optimize_posture"),
    "solve": ("workflow", "solve"),
    "validate": ("physics", "validate"),
    "read_pose": ("formats.posefile", "read_pose"),
    "write_pose": ("formats.posefile", "write_pose"),
    "build_urdf": ("model.urdf", "build_urdf"),
}
__all__ = sorted(_API) + ["__version__"]


def __getattr__(name: str) -> Any:
    if name not in _API:
        raise AttributeError(f"module 'op2motion' has no attribute {name!r}")
    module, attr = _API[name]
    return getattr(importlib.import_module(f".{module}", __name__), attr)
