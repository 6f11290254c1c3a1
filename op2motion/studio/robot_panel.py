"""The pose studio on a real (or emulated) OP2 (``op2motion studio --robot PORT``): the robot follows the pose being
edited at a capped speed (:class:`op2motion.bus.follow.Follower`: the 8 ms loop with its safety watch, goals clipped to
the mechanical ranges, at most :data:`~op2motion.bus.follow.FOLLOW_SPEED_RAD_S` per joint), and "read the pose from
the robot" makes the robot's present joint angles the pose (an edit like any other: refused from a tab that does not
edit, all or nothing). A fault stops the robot (the servos hold) and the page says why; editing goes on without it.
A mixin of :class:`.server.Studio`."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from op2motion.errors import InputError
from op2motion.studio.session import Readout, Session


class RobotPanel:
    """The robot's controls (see the module docstring); the page's parts come from :class:`.server.Studio`."""

    session: Session
    server: Any
    events: Any
    follower: Any
    _edit: Callable[..., None]

    def _build_robot_gui(self) -> None:
        """The robot's folder: where it is, and reading its pose (only with a robot)."""
        if self.follower is None:
            return
        gui = self.server.gui
        with gui.add_folder("robot"):
            self._robot_state = gui.add_markdown(f"robot on {self.follower.port}: following the pose")
            self._read_button = gui.add_button("read the pose from the robot")
            self._read_button.on_click(lambda e: self._edit("robot", self._read_robot, e))

    def _read_robot(self) -> Readout:
        pose = self.follower.pose() if self.follower is not None else None
        if pose is None:
            raise InputError("expected a robot that answers: no reading yet", "robot")
        self.session.servo = np.asarray(pose, dtype=float).copy()
        return self.session.readout()

    def _follow(self) -> None:
        """Hand the pose as it is now to the robot (after every change the page shows)."""
        if self.follower is None:
            return
        if not self.follower.running():
            report = getattr(self.follower, "report", None)
            why = getattr(report, "fault", None) or getattr(self.follower, "error", None) or "the loop ended"
            self._robot_state.content = f"**robot stopped** (the servos hold): {why}"
            return
        self.follower.set_target(self.session.servo.copy())
