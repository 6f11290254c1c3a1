"""The pose studio on an emulated OP2 (``studio --robot PORT``): the robot follows an edited joint at a capped speed,
the page reads the pose from the robot, and a tab that does not edit cannot move it."""

from __future__ import annotations

import time

import numpy as np
import pytest
from bus_support import lockstep
from helpers import POSES, wait_for

from op2motion.formats.posefile import read_pose
from op2motion.onrobot.follow import Follower
from op2motion.studio.folder import Workspace
from op2motion.studio.session import PoseEdit

pytestmark = pytest.mark.physics
TICK_DEG = 360.0 / 4096
FOLLOWED_DEG = 1.0              # the robot's goal ends within this of the edited angle [deg]
MOVE_DEG = 20.0                 # the large edit: 20° at the left elbow
JOG_DEG = 5.0                   # the small edit: one jog step
HOLD_S = 0.5                    # opened, the robot is watched this long for a move nobody asked for [s]
MOVE_TIMEOUT_S = 60.0           # a physics check and the move it allows end within this (a loaded machine) [s]
UPRIGHT_DEG = 20.0              # the torso tilt stays under this (walk-ready leans 12° forward) [deg]
HOT_AT_S = 0.5                  # the servo overheats this long after the loop's first goals [s]
FAULT_SAID_S = 2.0              # ... and the follower has said so within this [s]
FALLING_HIP_DEG = -80.0         # both hips pitched this far: the robot would fall on its face [deg]
SETTLE_S = 0.3                  # the joint reaches its goal this long after the goal does [s]


def _goals_deg(emulator, spec) -> np.ndarray:
    ticks = np.asarray(emulator.report()["goal_ticks"], dtype=float)
    return (ticks - spec.servo.center_tick) * TICK_DEG


def test_the_robot_moves_only_when_asked_checked_and_then_follows_and_is_read_back(spec, tmp_path):
    """Opened on a pose far from where the robot stands, nothing moves; asked, the robot makes a planned move
    checked in physics and stands in the pose; a jog-size edit is followed at the capped speed, a larger one is
    planned and checked again; a pose that falls in physics is refused and the robot holds; reading the robot
    brings its angles back."""
    pytest.importorskip("viser")
    from op2motion.studio.server import Studio

    with lockstep(spec, pace=1.0) as (emulator, port):     # held to the wall clock, as the page is
        follower = Follower(port, spec)
        follower.start()
        walkready = read_pose(POSES / "walkready.json", spec)
        studio = Studio(spec, PoseEdit(spec, walkready), workspace=Workspace(tmp_path), follower=follower)
        try:
            wait_for(lambda: follower.pose() is not None, "the first reading")
            held = _goals_deg(emulator, spec)
            time.sleep(HOLD_S)
            assert np.max(np.abs(_goals_deg(emulator, spec) - held)) < FOLLOWED_DEG, "moved before it was asked"
            assert "nothing moves" in studio._robot_state.content

            studio._edit("robot", studio._move_robot)
            wait_for(lambda: follower.state == "following the pose", "the checked move", timeout_s=MOVE_TIMEOUT_S)
            assert any("checked in physics" in text for kind, text in studio.events if kind == "robot")
            assert np.max(np.abs(_goals_deg(emulator, spec) - np.degrees(walkready.servo))) < FOLLOWED_DEG
            assert emulator.report()["truth"]["tilt_rad"] < np.radians(UPRIGHT_DEG)

            joint = "l_el"
            i = spec.joint_names.index(joint)
            start = float(np.degrees(walkready.servo[i]))
            studio._edit("jog", lambda: studio.session.jog(joint, JOG_DEG))          # within a jog: followed
            wait_for(lambda: abs(_goals_deg(emulator, spec)[i] - (start + JOG_DEG)) < FOLLOWED_DEG, "following")
            target = start + MOVE_DEG                                             # beyond a jog: checked again
            studio._edit("slider", lambda: studio.session.set_joint(joint, target))
            wait_for(lambda: abs(_goals_deg(emulator, spec)[i] - target) < FOLLOWED_DEG, "the second checked move",
                     timeout_s=MOVE_TIMEOUT_S)
            checks = sum("checking the move" in text for kind, text in studio.events if kind == "robot")
            assert checks == 2, "\n".join(map(str, studio.events))
            time.sleep(SETTLE_S)                                   # the joint follows its goal (a P controller)

            studio._edit("slider", lambda: studio.session.set_joint("l_hip_pitch", FALLING_HIP_DEG))
            studio._edit("slider", lambda: studio.session.set_joint("r_hip_pitch", FALLING_HIP_DEG))
            wait_for(lambda: follower.state.startswith("refused"), "the refusal", timeout_s=MOVE_TIMEOUT_S)
            assert "the robot holds" in studio._robot_state.content
            assert abs(_goals_deg(emulator, spec)[i] - target) < FOLLOWED_DEG
            assert emulator.report()["truth"]["tilt_rad"] < np.radians(UPRIGHT_DEG)

            studio.session.set_joint(joint, start)                 # the page's pose moves away from the robot's...
            studio._edit("robot", studio._read_robot)              # ...and reading the robot brings it back
            assert studio.session.servo[i] == pytest.approx(np.radians(target), abs=0.05)
            assert ("robot", "applied") in studio.events and follower.running()
        finally:
            studio.stop()
            follower.close()


def test_a_fault_while_following_is_said_at_once_in_words(spec):
    """A servo overheating while the robot holds in the studio: the follower says which servo, what, and what the
    robot does now, in words (never a repr), within a second of the fault."""
    from op2motion.bus.emulator.faults import Faults

    heard: list[str] = []
    with lockstep(spec, faults=Faults(overheat=[(13, HOT_AT_S, 85.0)]), pace=1.0) as (emulator, port):
        follower = Follower(port, spec, on_event=heard.append)
        follower.start()
        try:
            wait_for(lambda: not follower.running(), "the fault to stop the loop", timeout_s=HOT_AT_S + FAULT_SAID_S)
            said = heard[-1]
            assert said.startswith("robot stopped: ") and "(ID 13)" in said and "overheating" in said, said
            assert "hold" in said and "Fault(" not in said, said
            assert follower.state == said
        finally:
            follower.close()
