"""The walk controller: a planned gait played every 8 ms with stabilisation from the robot's IMU and joints
(:class:`WalkController`, all of it in :mod:`.stabilised`), and the way to the walk steered while it walks
(:meth:`WalkController.steerable`: :class:`.steer.SteerableWalk`, which shares the same stabilised walk).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from op2motion.gait.feedback import GYRO_GAINS_S, OPEN_LOOP, STOCK_GYRO_GAINS_S, Feedback
from op2motion.gait.stabilised import StabilisedWalk, attitude_of

if TYPE_CHECKING:
    from op2motion.formats.action import ActionFile
    from op2motion.gait.commands import CommandTimeline
    from op2motion.gait.steer import SteerableWalk
    from op2motion.robot.spec import Spec

__all__ = ["Feedback", "GYRO_GAINS_S", "OPEN_LOOP", "STOCK_GYRO_GAINS_S", "WalkController", "attitude_of"]


class WalkController(StabilisedWalk):
    """A planned gait played with attitude stabilisation (:class:`.stabilised.StabilisedWalk`): ``done`` once its plan
    has run out and the body has kept still; :meth:`stop` ends it early, on both feet side by side."""

    @classmethod
    def steerable(cls, spec: Spec | None = None, preset: str | None = None, feedback: Feedback = Feedback(),
                  commands: CommandTimeline | None = None, action: ActionFile | None = None) -> SteerableWalk:
        """A walk steered while it walks (:class:`.steer.SteerableWalk`, made by its
        :meth:`~.steer.SteerableWalk.make`): :meth:`~.steer.SteerableWalk.command` (vx [m/s], vy [m/s], yaw rate
        [rad/s]) at any tick, :meth:`~.steer.SteerableWalk.stop`; it stands while the command is zero. ``preset``
        (default ``steer``) gives the step's timing and shape; ``commands`` (a :class:`.commands.CommandTimeline`)
        feeds it by itself and gives its plan for a physics check; kicks are the stock pages of ``action`` when it
        has them."""
        from op2motion.gait.steer import SteerableWalk

        return SteerableWalk.make(spec, preset, feedback, commands, action)
