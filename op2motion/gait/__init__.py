"""Walking: footsteps, ZMP preview control, swing trajectories, the closed-form leg IK and the gait generator.

:func:`plan_gait` turns :class:`GaitParams` (or a preset, :func:`read_preset`) into a :class:`Gait`: joint goals
every 8 ms with the planned CoM, ZMP and feet; :func:`walk_physics` plays it in PyBullet and/or MuJoCo.
"""

from __future__ import annotations

from op2motion.gait.generator import Gait, plan_gait
from op2motion.gait.params import GaitParams, read_preset
from op2motion.gait.presets import PRESETS, preset_path
from op2motion.gait.report import gait_csv, gait_summary, gait_webots, walk_physics

__all__ = ["PRESETS", "Gait", "GaitParams", "gait_csv", "gait_summary", "gait_webots", "plan_gait",
           "preset_path", "read_preset", "walk_physics"]
