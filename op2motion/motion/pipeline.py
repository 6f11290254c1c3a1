"""The motion pipelines the command line and the API share.

* :func:`play_page`: an action page played tick for tick from a start pose (default: page 1's last step, the
  stock init pose) into a :class:`.trajectory.Trajectory`;
* :func:`plan_motion`: a motion file's poses planned into goals every 8 ms, refused if links pass through each
  other (:func:`.checks.require_clear`);
* :func:`motion_to_action`: a motion file as chained action pages written into an action file.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.errors import CheckFailed
from op2motion.formats.action import ActionFile, Page
from op2motion.formats.motionfile import Motion, PlannerName
from op2motion.motion.checks import OVERLAP_TOL_M, clearance, require_clear
from op2motion.motion.planner import action_pages, trajectory_through
from op2motion.motion.player import Playback, play, start_ticks
from op2motion.motion.trajectory import Trajectory, from_playback
from op2motion.motion.waypoint import Waypoint
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec

START_PAGE = 1                 # the stock file's page 1 ends in the init pose, where the framework starts


@dataclass(frozen=True)
class PlayedPage:
    """An action page played: the page, the pose it started from, what the player sent and the trajectory."""

    page: Page
    start: Pose
    playback: Playback
    trajectory: Trajectory


def play_page(action: ActionFile, page: int, spec: Spec, start: Pose | None = None) -> PlayedPage:
    """Play ``page`` of ``action`` from ``start`` (default: the last step of the file's page 1) as the robot's
    framework does, every 8 ms (:mod:`.player`)."""
    chosen = action.page(page, spec)
    start = start if start is not None else action.pose(START_PAGE, spec)
    playback = play(action, page, start_ticks(start.servo, spec))
    return PlayedPage(chosen, start, playback, from_playback(playback, spec, chosen.name))


def waypoints_of(motion: Motion) -> list[Waypoint]:
    """The planner's waypoints of a motion file's steps."""
    return [Waypoint(s.pose.name, s.pose.servo, s.duration_s, s.pause_s, s.pose.support) for s in motion.steps]


def plan_motion(motion: Motion, spec: Spec, planner: PlannerName = "rrt", seed: int = 0) -> Trajectory:
    """A motion's goals every 8 ms with its profile and P gain, weight shifts inserted, segments whose straight
    line collides planned around (``planner`` "rrt", seeded by ``seed``: :mod:`.route`); refused (naming segment,
    time and links) where links would still pass through each other (``planner`` "none")."""
    waypoints = waypoints_of(motion)
    require_poses_clear(waypoints, spec)
    trajectory = trajectory_through(waypoints, spec, motion.profile, motion.p_gain, planner=planner, seed=seed)
    require_clear(trajectory, spec)
    return trajectory


def require_poses_clear(waypoints: list[Waypoint], spec: Spec) -> None:
    """Refuse a motion through a pose whose own links pass through each other (deeper than
    :data:`~.checks.OVERLAP_TOL_M`): no seed, no planner and no pose in between can help; the pose must change."""
    least, links = clearance(np.array([w.servo for w in waypoints]), spec)
    bad = np.flatnonzero(least < -OVERLAP_TOL_M)
    if bad.size:
        k = int(bad[0])
        raise CheckFailed(f"pose {waypoints[k].name} itself has {links[k][0]} and {links[k][1]} "
                          f"{-least[k] * 1000:.0f} mm through each other: no path can reach it; move them apart in "
                          f"the pose")


@dataclass(frozen=True)
class MotionPages:
    """A motion written as chained action pages: the ``action`` file with them, the ``pages`` written (the first
    plays the motion) and the planner's ``notes``."""

    action: ActionFile
    pages: tuple[int, ...]
    notes: tuple[str, ...]


def motion_to_action(motion: Motion, spec: Spec, base: ActionFile, first: int | None = None,
                     force: bool = False, planner: PlannerName = "rrt", seed: int = 0) -> MotionPages:
    """``base`` with the motion written as chained pages (at most 7 steps each, linked by ``next``) from ``first``
    on (default: the first run of empty pages; occupied pages refused unless ``force``), colliding segments planned
    around as :func:`plan_motion` does (see :class:`MotionPages`)."""
    waypoints = waypoints_of(motion)
    count = len(action_pages(waypoints, spec, motion.name, 1, motion.p_gain, planner=planner, seed=seed)[0])
    first = base.first_empty_run(count) if first is None else first
    pages, notes = action_pages(waypoints, spec, motion.name, first, motion.p_gain, planner=planner, seed=seed)
    done = base.with_pages(pages, first, force)
    return MotionPages(done.action, tuple(range(done.first, done.first + len(pages))), tuple(notes))
