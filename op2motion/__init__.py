"""op2motion: whole-body motion generation for the ROBOTIS OP2 humanoid, checked in physics.

The public API (imported on first use, so ``import op2motion`` does no work)::

    import op2motion as op2
    spec = op2.load_spec()                                        # the shipped OP2 spec
    pose = op2.read_pose("poses/walkready.json", spec)
    points = op2.forward(pose.book(spec), spec)                   # body points, lumped CoM
    report = op2.check(op2.Schedule.hold(pose.servo, pose.support, spec), spec)    # physics
    outcome = op2.solve(op2.PostureProblem("left", "left", (0.10, 0.05, 0.07)), spec)
    played = op2.play_page(op2.ActionFile.read("motion_4096.bin"), 9, spec)        # an action page
    traj = op2.plan_waypoints([op2.Waypoint("a", qa, 0, 0, "double"), op2.Waypoint("b", qb, 2, 0, "double")], spec)
    line = op2.line_move(pose, op2.LineRequest("right", 1.0, delta_m=(0.05, 0, 0)), spec)    # a hand in a line
    gait = op2.plan_gait(op2.load_preset("forward"), spec)        # a walk; op2.gait_schedule(gait, spec) plays it
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
    "Support": ("robot.support", "Support"),
    "forward": ("kinematics", "forward"),
    "stability_margin": ("robot.balance", "stability_margin"),
    "solve_arm_ik": ("kinematics.arm_ik", "solve_arm_ik"),
    "PostureProblem": ("posture.cost", "PostureProblem"),
    "PSOSettings": ("posture.pso", "PSOSettings"),
    "optimize_posture": ("posture.solve", "optimize_posture"),
    "solve": ("workflow", "solve"),
    "Validate": ("workflow", "Validate"),
    "check": ("physics", "check"),
    "Controller": ("physics", "Controller"),
    "Schedule": ("physics", "Schedule"),
    "Plan": ("physics", "Plan"),
    "Pushes": ("physics", "Pushes"),
    "Trials": ("physics", "Trials"),
    "Setup": ("physics", "Setup"),
    "read_pose": ("formats.posefile", "read_pose"),
    "write_pose": ("formats.posefile", "write_pose"),
    "ActionFile": ("formats.action", "ActionFile"),
    "read_motion": ("formats.motionfile", "read_motion"),
    "play_page": ("motion.pipeline", "play_page"),
    "plan_motion": ("motion.pipeline", "plan_motion"),
    "Waypoint": ("motion.waypoint", "Waypoint"),
    "plan_waypoints": ("motion.planner", "plan"),
    "route": ("motion.route", "route"),
    "LineRequest": ("motion.cartesian", "LineRequest"),
    "line_move": ("motion.cartesian", "line_move"),
    "load_preset": ("gait", "load_preset"),
    "plan_gait": ("gait", "plan_gait"),
    "gait_schedule": ("gait", "gait_schedule"),
    "build_library": ("library.build", "build_library"),
    "build_urdf": ("model.urdf", "build_urdf"),
}
__all__ = sorted(_API) + ["__version__"]


def __getattr__(name: str) -> Any:
    if name not in _API:
        raise AttributeError(f"module 'op2motion' has no attribute {name!r}")
    module, attr = _API[name]
    return getattr(importlib.import_module(f"op2motion.{module}"), attr)
