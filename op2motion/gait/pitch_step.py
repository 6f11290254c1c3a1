"""Stepping against a forward (or backward) fall: the swing foot lands where the torso's pitch error says.

A body that pitches forward of its plan (soft servos that sag under a fast stride, a torso heavier in front than
modelled) carries its centre of mass ahead of the planned support; the plan's next footstep then lands behind it and
the fall grows step by step. :class:`PitchStep` moves each swing foot along the torso's planned heading by

    ``gain`` [m/rad] x (pitch error [rad] + ``lead`` [s] x pitch rate [rad/s])

(the error is the estimated pitch less the plan's, positive leaning forward), at most :data:`MAX_PITCH_STEP_M`,
phased in over the swing from where that foot stood. A landed foot keeps its move while it stands (its sole is held
there, relative to the torso's plan, until it swings again): pulling it back to the plan's place under the body would
carry the torso forward over it by the same amount and undo the step.

The gains come from the preset (``pitch_step_m_rad``, ``pitch_step_lead_s``, :mod:`.params`); 0 turns it off, and
then the controller's footsteps are the plan's as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from op2motion.robot.support import SIDES

MAX_PITCH_STEP_M = 0.025     # a swing foot is moved at most this far along the heading [m]


@dataclass
class PitchStep:
    """The sagittal step adjustment (see the module docstring).

    Attributes:
        gain_m_rad: landing move per radian of pitch error [m/rad] (0: off).
        lead_s: the pitch is extrapolated this far by its rate [s].
        live: the move a swing foot is heading for now [m] (along the planned heading).
        held: per side, that foot's move [m]: where it landed (or is swinging to, by the swing phase).
        start: per side, its move when its swing began [m].
        swinging: per side, whether it was swinging at the last row seen.
    """

    gain_m_rad: float = 0.0
    lead_s: float = 0.0
    live: float = 0.0
    held: dict[str, float] = field(default_factory=lambda: {side: 0.0 for side in SIDES})
    start: dict[str, float] = field(default_factory=lambda: {side: 0.0 for side in SIDES})
    swinging: dict[str, bool] = field(default_factory=lambda: {side: False for side in SIDES})

    @property
    def active(self) -> bool:
        """Does it move any foot?"""
        return self.gain_m_rad > 0.0

    def reset(self) -> None:
        """Every foot back on its plan."""
        self.live = 0.0
        for side in SIDES:
            self.held[side], self.start[side], self.swinging[side] = 0.0, 0.0, False

    def update(self, pitch_error_rad: float, pitch_rate_rad_s: float, contact: str, phase: float) -> None:
        """One control row: the torso's pitch error [rad] and rate [rad/s], the plan's ``contact`` (``double``, or
        the standing side) and swing ``phase`` (0 -> 1 across the single support)."""
        if not self.active:
            return
        wanted = self.gain_m_rad * (pitch_error_rad + self.lead_s * pitch_rate_rad_s)
        self.live = float(np.clip(wanted, -MAX_PITCH_STEP_M, MAX_PITCH_STEP_M))
        for side in SIDES:
            swings = contact not in ("double", side)
            if swings and not self.swinging[side]:
                self.start[side] = self.held[side]
            if swings:
                self.held[side] = (1.0 - phase) * self.start[side] + phase * self.live
            self.swinging[side] = swings

    def move(self, side: str, heading_rad: float) -> np.ndarray:
        """The ``side`` sole's move (3,) [m] in the world frame, along the planned torso heading [rad]."""
        if not self.active:
            return np.zeros(3)
        value = self.held[side]
        return np.array([value * math.cos(heading_rad), value * math.sin(heading_rad), 0.0])
