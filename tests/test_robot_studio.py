"""The pose studio on an emulated OP2 (``studio --robot PORT``): the robot follows an edited joint at a capped speed,
the page reads the pose from the robot, and a tab that does not edit cannot move it."""

from __future__ import annotations

import time

import numpy as np
import pytest
from bus_support import lockstep
from helpers import POSES, wait_for

from op2motion.bus.follow import FOLLOW_SPEED_RAD_S, Follower
from op2motion.formats.posefile import read_pose
from op2motion.studio.folder import Workspace
from op2motion.studio.session import Session

pytestmark = pytest.mark.physics
TICK_DEG = 360.0 / 4096
FOLLOWED_DEG = 1.0              # the robot's goal ends within this of the edited angle [deg]
MOVE_DEG = 20.0                 # the edit: 20° at the left elbow
SETTLE_S = 0.3                  # the joint reaches its goal this long after the goal does [s]


def _goal_deg(emulator, spec, joint: str) -> float:
    ticks = emulator.report()["goal_ticks"][spec.joint_names.index(joint)]
    return (ticks - spec.servo.center_tick) * TICK_DEG


def test_the_robot_follows_the_studio_and_is_read_back(spec, tmp_path):
    pytest.importorskip("viser")
    from op2motion.studio.server import Studio

    with lockstep(spec, pace=1.0) as (emulator, port):     # held to the wall clock, as the page is
        follower = Follower(port, spec)
        follower.start()
        studio = Studio(spec, Session(spec, read_pose(POSES / "walkready.json", spec)), workspace=Workspace(tmp_path),
                        follower=follower)
        try:
            joint = "l_el"
            wait_for(lambda: follower.pose() is not None, "the first reading")
            start = float(np.degrees(follower.pose()[spec.joint_names.index(joint)]))
            target = start + MOVE_DEG
            studio._edit("slider", lambda: studio.session.set_joint(joint, target))
            assert abs(_goal_deg(emulator, spec, joint) - target) > FOLLOWED_DEG      # capped: not there at once
            wait_for(lambda: abs(_goal_deg(emulator, spec, joint) - target) < FOLLOWED_DEG, "the robot following",
                     timeout_s=10 * MOVE_DEG / np.degrees(FOLLOW_SPEED_RAD_S))
            time.sleep(SETTLE_S)                                   # the joint follows its goal (a P controller)
            studio.session.set_joint(joint, start)                 # the page's pose moves away from the robot's...
            studio._edit("robot", studio._read_robot)              # ...and reading the robot brings it back
            assert studio.session.servo[spec.joint_names.index(joint)] == pytest.approx(np.radians(target), abs=0.05)
            assert ("robot", "applied") in studio.events and follower.running()
        finally:
            studio.stop()
            follower.close()
