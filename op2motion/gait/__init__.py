"""Walking: footsteps, ZMP preview control, swing trajectories, the closed-form leg IK and the gait generator.

:func:`generate_gait` turns :class:`GaitParams` (or a preset, :func:`read_preset`) into a :class:`Gait`: joint goals
every 8 ms with the planned CoM, ZMP and feet; :func:`gait_schedule` makes it the controller that
:func:`op2motion.physics.check` plays in PyBullet and/or MuJoCo, and :func:`walk_summary` reports the walk.
:class:`WalkController` plays a plan with feedback; ``SteerableWalk.make()`` is the walk you steer while it
walks (:mod:`.steer`), fed by :meth:`~.steer.SteerableWalk.command` or a :class:`CommandTimeline`.
"""

from __future__ import annotations

from op2motion.gait.commands import CommandTimeline, read_commands, timeline_of
from op2motion.gait.controller import WalkController
from op2motion.gait.envelope import STEER_ENVELOPE, Envelope
from op2motion.gait.generator import Gait, generate_gait
from op2motion.gait.measures import WALK_HOLD_S, WALK_SETTLE_S, WalkMeasures, walk_measures
from op2motion.gait.params import GaitParams, read_preset
from op2motion.gait.presets import PRESETS, load_preset, preset_path
from op2motion.gait.report import gait_csv, gait_summary, gait_webots, side_pushes, walk_summary
from op2motion.gait.schedule import gait_schedule, plan_of_gait
from op2motion.gait.steer import SteerableWalk

__all__ = ["PRESETS", "STEER_ENVELOPE", "WALK_HOLD_S", "WALK_SETTLE_S", "CommandTimeline", "Envelope", "Gait",
           "GaitParams", "WalkController", "WalkMeasures", "walk_measures",
           "gait_csv", "plan_of_gait", "gait_schedule", "gait_summary", "gait_webots", "load_preset", "generate_gait",
           "SteerableWalk", "preset_path", "read_commands", "read_preset", "side_pushes", "timeline_of", "walk_summary"]
