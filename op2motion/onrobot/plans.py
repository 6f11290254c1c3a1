"""What the robot plays, made from op2motion's own motions and checked before it moves.

* :func:`move`: from where the robot is to a pose, planned within the servos' speed
  (:func:`op2motion.motion.planner.trajectory_through`: quintic, every joint under half the MX-28's no-load speed,
  weight shifts where the support changes, collisions planned around);
* :func:`then`: two trajectories one after the other (the second starting where the first ends);
* :func:`page_start` and :func:`page_trajectory`: an action page's first pose, and the page played from it tick for
  tick as the framework plays it (:func:`op2motion.motion.pipeline.play_page`);
* :func:`physics_problem`: the whole trajectory in physics (MuJoCo, the servo model): what goes wrong, in words,
  or None;
* :func:`robot_schedule`: the trajectory as the controller the loop runs, without the physics check's settling
  time before it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from op2motion.motion.trajectory import Trajectory
from op2motion.physics import Plan, Schedule
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support, SupportName

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile
    from op2motion.physics import EngineName

MIN_MOVE_S = 0.6                   # a move to the first pose takes at least this long (longer if the speed says so)
HOLD_AFTER_S = 0.3                 # the last goal is sent this long after a motion's last row
LYING_TILT_RAD = math.radians(60.0)   # tilted this far the robot lies: physics cannot check a motion from there yet
READY_HIP_LOWER_M = 0.02           # the via pose's hips below straight legs (the stock gait's walk-ready height)
CHECK_ENGINE: EngineName = "mujoco"    # the faster engine checks what the robot is about to play


def ready_pose(spec: Spec) -> Pose:
    """The gait's standing pose (both feet under the hips, knees bent): the via pose of a move the planner cannot
    make directly (from straight legs onto one foot, the weight shift it inserts has the arms through the torso)."""
    from dataclasses import replace

    from op2motion.gait import generate_gait, load_preset

    params = replace(load_preset(None).with_steps(1), hip_lower_m=READY_HIP_LOWER_M)
    return Pose("ready", Support.DOUBLE, generate_gait(params, spec).joints[0])


def move(current: np.ndarray, target: Pose, spec: Spec, support: Support | SupportName = Support.DOUBLE) -> Trajectory:
    """From ``current`` servo angles (20,) [rad] (the robot on ``support``) to ``target``, within the servos'
    speed; through :func:`ready_pose` where no direct way is found."""
    from op2motion.errors import CheckFailed
    from op2motion.motion.planner import trajectory_through
    from op2motion.motion.waypoint import Waypoint

    here = Waypoint("present", np.asarray(current, dtype=float), 0.0, 0.0, Support.of(support))
    there = Waypoint(target.name, target.servo, MIN_MOVE_S, 0.0, target.support)
    try:
        return trajectory_through([here, there], spec)
    except CheckFailed as direct:
        ready = ready_pose(spec)
        try:
            via = Waypoint(ready.name, ready.servo, MIN_MOVE_S, 0.0, ready.support, stop=True)
            return trajectory_through([here, via, there], spec)
        except CheckFailed:
            raise direct from None


def then(first: Trajectory, second: Trajectory) -> Trajectory:
    """``first`` and then ``second`` (whose first row repeats ``first``'s last and is dropped)."""
    offset = len(first.segment_names)
    segment = np.where(second.segment[1:] < 0, -1, second.segment[1:] + offset)
    return Trajectory(np.vstack([first.goals, second.goals[1:]]), np.vstack([first.p_gains, second.p_gains[1:]]),
                      first.supports + second.supports[1:], np.concatenate([first.segment, segment]),
                      first.segment_names + second.segment_names, first.dt, first.notes + second.notes)


def page_start(action: ActionFile, page: int, spec: Spec, current: np.ndarray) -> Pose:
    """The first step of action page ``page`` as a double-support pose (joints it leaves out stay where they are
    now, ``current`` (20,) [rad])."""
    from op2motion.bus.robot import angle_of

    chosen = action.page(page, spec)
    servo = np.asarray(current, dtype=float).copy()
    if chosen.steps:
        for i, joint in enumerate(spec.joints):
            tick = chosen.steps[0].ticks.get(joint.id)
            if tick is not None:
                servo[i] = angle_of(tick, spec)
    return Pose(f"page{page}_start", Support.DOUBLE, servo)


def page_trajectory(action: ActionFile, page: int, spec: Spec, start: Pose) -> Trajectory:
    """Action page ``page`` played from ``start`` as the framework plays it (8 ms ticks, its own profile)."""
    from op2motion.motion.pipeline import play_page

    return play_page(action, page, spec, start).trajectory


def physics_problem(trajectory: Trajectory, spec: Spec, on_progress: Any = None) -> str | None:
    """The trajectory played in physics (:data:`CHECK_ENGINE`, the servo model, from the first row standing): what
    goes wrong, in words (the judge's), or None."""
    from op2motion.physics import check

    report = check(trajectory.schedule(spec), spec, (CHECK_ENGINE,), on_progress=on_progress)
    return report.problem("does not get through")


def robot_schedule(trajectory: Trajectory, spec: Spec) -> Schedule:
    """The trajectory as the loop runs it: row 0 at once, a row every 8 ms, the last held :data:`HOLD_AFTER_S`."""
    end = (len(trajectory.goals) - 1) * trajectory.dt
    plan = Plan("motion", trajectory.goals, trajectory.p_gains, tuple(Support.of(s) for s in trajectory.supports),
                trajectory.dt, 0.0, end + HOLD_AFTER_S)
    return Schedule(plan, spec.joint_names)
