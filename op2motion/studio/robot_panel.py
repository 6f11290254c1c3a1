"""The pose studio on a real (or emulated) OP2 (``op2motion studio --robot PORT``), under the robot's safety contract
(:class:`op2motion.onrobot.follow.Follower`): opening the studio moves nothing; "move the robot to the pose" makes the
same planned move ``robot play`` makes, checked in physics from where the robot stands, and from then on the robot
follows edits within a jog step of the pose it was checked to (goals clipped to the mechanical ranges, at most
:data:`~op2motion.onrobot.follow.FOLLOW_SPEED_RAD_S` per joint); a larger edit is planned and checked again. "read the
pose from the robot" makes the robot's present joint angles the pose. Both buttons are edits like any other: refused
from a tab that does not edit. What the robot does (holding, checking, moving, refused, a fault and what it does
now) shows on the page in words as it happens; editing goes on without the robot. A mixin of
:class:`.server.Studio`."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.studio.session import PoseEdit, Readout


class RobotPanel:
    """The robot's controls (see the module docstring); the page's parts come from :class:`.server.Studio`."""

    session: PoseEdit
    server: Any
    events: Any
    follower: Any
    _edit: Callable[..., None]

    def _build_robot_gui(self) -> None:
        """The robot's folder: what it does, moving it to the pose, reading its pose (only with a robot)."""
        if self.follower is None:
            return
        gui = self.server.gui
        with gui.add_folder("robot"):
            self._robot_state = gui.add_markdown(f"**robot**: {self.follower.state}")
            self._move_button = gui.add_button("move the robot to the pose (checked in physics)")
            self._move_button.on_click(lambda e: self._edit("robot", self._move_robot, e))
            self._read_button = gui.add_button("read the pose from the robot")
            self._read_button.on_click(lambda e: self._edit("robot", self._read_robot, e))
        self.follower.on_event = self._robot_said

    def _robot_said(self, text: str) -> None:
        """What the robot does, on the page at once (from the follower's threads)."""
        self._robot_state.content = f"**robot**: {text}"
        self.events.append(("robot", text))

    def _move_robot(self) -> Readout:
        self.follower.move_to(self.session.pose())
        return self.session.readout()

    def _read_robot(self) -> Readout:
        pose = self.follower.pose() if self.follower is not None else None
        if pose is None:
            raise InputError("expected a robot that answers: no reading yet", "robot")
        self.session.servo = np.asarray(pose, dtype=float).copy()
        return self.session.readout()

    def _follow(self) -> None:
        """Hand the pose as it is now to the robot (after every change the page shows): followed, or planned and
        checked again, or nothing before the robot was first moved to a pose."""
        if self.follower is None or not self.follower.running():
            return
        self.follower.request(self.session.pose())
