"""The ways up: which motion gets the robot up from each way it lies, as goals every 8 ms from where it is.

* from the front (face down) and the back (face up): the stock pages 10 (``f up``) and 11 (``b up``) of the user's
  action file when it has them (played as the robot's framework plays them, :mod:`.player`, from the joints' present
  angles), else op2motion's own get-up motions ``getup_front`` and ``getup_back``;
* from a side: op2motion's own ``roll_left`` / ``roll_right``, which roll the robot onto its back (then it gets up from
  there).

op2motion's motions are motion files (``poses/motions/``, shipped with the package as ``op2motion.motions``),
planned like every motion (:func:`.pipeline.plan_motion`: quintic, at half the servos' no-load speed, refused if links
pass through each other) once, and led in by a quintic from the present joint angles to their first pose
(:func:`.planner.blend`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from op2motion.errors import InputError, Op2MotionError
from op2motion.formats.action import ActionFile
from op2motion.motion.player import IDS, play, start_ticks
from op2motion.robot.joints import ticks_to_servo
from op2motion.robot.spec import Spec

OWN = {"front": "getup_front", "back": "getup_back", "left": "roll_left", "right": "roll_right"}
STOCK_PAGES = {"front": 10, "back": 11}        # the stock action file's get-up pages (bus_notes: framework demos)
BLEND_LEAST_S = 0.5                            # the lead-in to a motion's first pose takes at least this [s]


def motion_path(name: str) -> Path:
    """The file of one of op2motion's own motions (``poses/motions/NAME.json`` in the source tree, else the
    installed package's ``op2motion.motions``)."""
    source = Path(__file__).resolve().parents[2] / "poses" / "motions" / f"{name}.json"
    if source.is_file():
        return source
    try:
        from importlib import resources

        found = resources.files("op2motion.motions").joinpath(f"{name}.json")
        if found.is_file():
            return Path(str(found))
    except (ModuleNotFoundError, FileNotFoundError):
        pass
    raise InputError(f"expected op2motion's motion {name!r} in poses/motions or the installed package, got none",
                     "motion")


@dataclass(frozen=True)
class Way:
    """A way up from one side: its name, goals (K, 20) [rad] and P gains (K, 20), starting from where the robot
    was when it was chosen."""

    name: str
    goals: np.ndarray
    p_gains: np.ndarray


class Ways:
    """The ways up of a robot (see the module docstring); ``action``: an action file whose pages 10 and 11 to use."""

    def __init__(self, spec: Spec, action: ActionFile | None = None):
        self.spec, self.action = spec, action
        self._own: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def stock(self, side: str) -> int | None:
        """The page of the action file that gets up from ``side``, if it has a playable one."""
        page = STOCK_PAGES.get(side)
        if self.action is None or page is None or not self.action.raw(page).playable:
            return None
        return page

    def own(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        """op2motion's motion from ``side`` planned (goals (K, 20) [rad], P gains (K, 20)), once."""
        if side not in self._own:
            from op2motion.formats.motionfile import read_motion
            from op2motion.motion.pipeline import plan_motion

            trajectory = plan_motion(read_motion(motion_path(OWN[side]), self.spec), self.spec, planner="none")
            self._own[side] = (trajectory.goals, trajectory.p_gains)
        return self._own[side]

    def way(self, side: str, joints: np.ndarray) -> Way:
        """The way up from ``side`` (``front``, ``back``, ``left``, ``right``) for a robot whose joints are at
        ``joints`` (20,) [rad]."""
        if side not in OWN:
            raise InputError(f"expected one of {', '.join(OWN)}, got {side!r}", "side")
        page = self.stock(side)
        if page is not None:
            if self.action is None:
                raise Op2MotionError("a stock page without its action file")
            playback = play(self.action, page, start_ticks(joints, self.spec))
            order = [IDS.index(j.id) for j in self.spec.joints]
            goals = np.array([ticks_to_servo(row[order], self.spec) for row in playback.goals[1:]])
            return Way(f"stock page {page}", goals, playback.p_gains[1:, order].astype(float))
        from op2motion.motion.planner import blend

        goals, gains = self.own(side)
        lead = blend(joints, goals[0], self.spec, BLEND_LEAST_S)
        return Way(OWN[side], np.vstack([lead, goals]), np.vstack([np.repeat(gains[:1], len(lead), 0), gains]))
