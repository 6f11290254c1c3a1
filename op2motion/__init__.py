"""op2motion: whole-body motion generation for the ROBOTIS OP2 humanoid, checked in physics.

The public API (imported on first use, so ``import op2motion`` does no work)::

    import op2motion as op2
    spec = op2.load_spec()                                        # the shipped OP2 spec
    pose = op2.read_pose("poses/walkready.json", spec)
    points = op2.forward(pose.book(spec), spec)                   # body points, lumped CoM
    report = op2.check(op2.Schedule.hold(pose.servo, pose.support, spec), spec)    # physics
    outcome = op2.solve(op2.PostureProblem("left", "left", (0.10, 0.05, 0.07)), spec)
    played = op2.play_page(op2.ActionFile.read("motion_4096.bin"), 9, spec)        # an action page
    traj = op2.trajectory_through([op2.Waypoint("a", qa, 0, 0, "double"), op2.Waypoint("b", qb, 2, 0, "double")], spec)
    line = op2.line_move(pose, op2.LineRequest("right", 1.0, delta_m=(0.05, 0, 0)), spec)    # a hand in a line
    gait = op2.generate_gait(op2.load_preset("forward"), spec)        # a walk; op2.gait_schedule(gait, spec) plays it
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from op2motion.version import __version__

if TYPE_CHECKING:                     # what editors and type checkers see; at run time, __getattr__ imports on use
    from op2motion.errors import Op2MotionError as Op2MotionError
    from op2motion.formats.action import ActionFile as ActionFile
    from op2motion.formats.motionfile import Motion as Motion
    from op2motion.formats.motionfile import read_motion as read_motion
    from op2motion.formats.posefile import read_pose as read_pose
    from op2motion.formats.posefile import write_pose as write_pose
    from op2motion.gait import gait_schedule as gait_schedule
    from op2motion.gait import generate_gait as generate_gait
    from op2motion.gait import load_preset as load_preset
    from op2motion.gait.generator import Gait as Gait
    from op2motion.gait.params import GaitParams as GaitParams
    from op2motion.kinematics import forward as forward
    from op2motion.kinematics.arm_ik import ArmIKResult as ArmIKResult
    from op2motion.kinematics.arm_ik import solve_arm_ik as solve_arm_ik
    from op2motion.kinematics.points import BodyPoints as BodyPoints
    from op2motion.library.build import BuildSummary as BuildSummary
    from op2motion.library.build import build_library as build_library
    from op2motion.model.urdf import build_urdf as build_urdf
    from op2motion.motion.cartesian import LineMove as LineMove
    from op2motion.motion.cartesian import LineRequest as LineRequest
    from op2motion.motion.cartesian import line_move as line_move
    from op2motion.motion.pipeline import PlayedPage as PlayedPage
    from op2motion.motion.pipeline import plan_motion as plan_motion
    from op2motion.motion.pipeline import play_page as play_page
    from op2motion.motion.planner import trajectory_through as trajectory_through
    from op2motion.motion.route import Routed as Routed
    from op2motion.motion.route import route as route
    from op2motion.motion.trajectory import Trajectory as Trajectory
    from op2motion.motion.waypoint import Waypoint as Waypoint
    from op2motion.physics import Controller as Controller
    from op2motion.physics import Plan as Plan
    from op2motion.physics import Pushes as Pushes
    from op2motion.physics import Schedule as Schedule
    from op2motion.physics import Setup as Setup
    from op2motion.physics import Trials as Trials
    from op2motion.physics import check as check
    from op2motion.physics.report import CheckReport as CheckReport
    from op2motion.posture.cost import PostureProblem as PostureProblem
    from op2motion.posture.pso import PSOSettings as PSOSettings
    from op2motion.posture.solve import PostureResult as PostureResult
    from op2motion.posture.solve import optimize_posture as optimize_posture
    from op2motion.robot.balance import stability_margin as stability_margin
    from op2motion.robot.joints import BookAngles as BookAngles
    from op2motion.robot.joints import book_to_servo as book_to_servo
    from op2motion.robot.joints import servo_to_book as servo_to_book
    from op2motion.robot.pose import Pose as Pose
    from op2motion.robot.spec import Spec as Spec
    from op2motion.robot.specfile import load_spec as load_spec
    from op2motion.robot.support import Support as Support
    from op2motion.workflow import Outcome as Outcome
    from op2motion.workflow import Validate as Validate
    from op2motion.workflow import solve as solve

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
    "trajectory_through": ("motion.planner", "trajectory_through"),
    "route": ("motion.route", "route"),
    "LineRequest": ("motion.cartesian", "LineRequest"),
    "line_move": ("motion.cartesian", "line_move"),
    "load_preset": ("gait", "load_preset"),
    "generate_gait": ("gait", "generate_gait"),
    "gait_schedule": ("gait", "gait_schedule"),
    "build_library": ("library.build", "build_library"),
    "build_urdf": ("model.urdf", "build_urdf"),
    # the results they return
    "Spec": ("robot.spec", "Spec"),
    "BodyPoints": ("kinematics.points", "BodyPoints"),
    "ArmIKResult": ("kinematics.arm_ik", "ArmIKResult"),
    "PostureResult": ("posture.solve", "PostureResult"),
    "Outcome": ("workflow", "Outcome"),
    "CheckReport": ("physics.report", "CheckReport"),
    "Motion": ("formats.motionfile", "Motion"),
    "PlayedPage": ("motion.pipeline", "PlayedPage"),
    "Trajectory": ("motion.trajectory", "Trajectory"),
    "Routed": ("motion.route", "Routed"),
    "LineMove": ("motion.cartesian", "LineMove"),
    "GaitParams": ("gait.params", "GaitParams"),
    "Gait": ("gait.generator", "Gait"),
    "BuildSummary": ("library.build", "BuildSummary"),
}
__all__ = [*sorted(_API), "__version__"]


def __getattr__(name: str) -> Any:
    if name not in _API:
        raise AttributeError(f"module 'op2motion' has no attribute {name!r}")
    module, attr = _API[name]
    return getattr(importlib.import_module(f"op2motion.{module}"), attr)
