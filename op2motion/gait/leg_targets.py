"""The legs' goals when the body turns and the soles move: the part of the walk controller that goes through the
closed-form leg IK every 8 ms (:class:`LegTargets`, a base of :class:`.controller.WalkController`).

Per tick, per leg: where the sole is to be (the plan's; a swing sole steered about the stance sole by the heading
loop and moved against the feet's placement error; a landed sole held where it landed; a shaped swing sole levelled
and its toe raised, :mod:`.swing_foot`), where the body is (the plan's, turned about the support point by the
stabiliser), and the leg's servo change from its planned angles. Single vectors and rotations are floats
(:mod:`op2motion.kinematics.small`): on 3-vectors NumPy's call overhead made this a tenth of a walk check.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from op2motion.gait.rows import REACH_SHARE, RowBuffer
from op2motion.gait.swing_foot import toe_raised
from op2motion.kinematics import small
from op2motion.kinematics.leg_ik import Leg, leg_ik_pose, within_reach_pose
from op2motion.robot.support import SIDES, Side, SupportName, other_side


class LegTargets:
    """The leg-goal methods of a walk controller. The controller provides ``rows`` (its :class:`.rows.RowBuffer`),
    ``legs`` (side -> :class:`~op2motion.kinematics.leg_ik.Leg`), ``_leg_servos`` (side -> servo indices),
    ``_names`` (the servos), ``feedback``, ``params``, ``spec``, ``state`` (with the last attitude error) and
    ``odometry``."""

    rows: RowBuffer
    legs: dict[str, Leg]
    _leg_servos: dict[str, np.ndarray]
    _names: tuple[str, ...]
    feedback: Any
    params: Any
    spec: Any
    state: Any
    odometry: Any

    @property
    def _swing_shaped(self) -> bool:
        """Does the preset shape the swing foot (:mod:`.swing_foot`)?"""
        return bool(self.params.swing_level or self.params.swing_level_roll or self.params.swing_toe_deg)

    def _landed(self, side: Side, k: int) -> tuple[small.Vec3, float] | None:
        """Where the ``side`` foot is held instead of its plan (its measured landing's miss: position (3,) [m] and
        yaw [rad]) at gait row ``k``, or None: after the closing step, the landed foot where it landed."""
        last = self.odometry.last
        if self.feedback.accept_landing and last is not None and last[0] == side:
            return (float(last[1][0]), float(last[1][1]), 0.0), float(last[2])
        return None

    def _leg_change(self, k: int, pitch: float, roll: float, heading: float = 0.0) -> np.ndarray:
        """The servo change (20,) [rad] that turns the whole body by (pitch, roll) [rad] about the support point,
        the soles staying where the plan puts them, and the swing sole turned by ``heading`` [rad] about the stance
        sole's centre (in full at landing) and moved against the feet's placement error (leg odometry); after the
        closing step, the landed sole where it landed. Single vectors and rotations as floats (:mod:`.small`)."""
        rows = self.rows
        pos, rot = rows.get("torso_pos", k).tolist(), rows.get("torso_rot", k).tolist()
        pivot, turn = rows.get("support_point", k).tolist(), small.mul(small.rot_y(pitch), small.rot_x(roll))
        moved_pos, moved_rot = small.add(pivot, small.apply(turn, small.sub(pos, pivot))), small.mul(turn, rot)
        contact = rows.obj("contact", k)
        phase = rows.value("swing_phase", k)
        out = np.zeros(len(self._names))
        for side in SIDES:
            leg = self.legs[side]
            swinging = contact not in ("double", side)
            sole, sole_rot = self._sole_target(side, k, contact, phase, heading if swinging else 0.0)
            body_pos, body_rot = moved_pos, moved_rot
            if swinging and self._swing_shaped:
                sole, sole_rot = toe_raised(sole, sole_rot, phase, math.radians(self.params.swing_toe_deg),
                                            self.spec.sole_extents(side)[1])
                error = self.state.error
                tilt = small.mul(small.rot_y(self.params.swing_level * float(error[0])),
                                 small.rot_x(self.params.swing_level_roll * float(error[1])))
                body_pos = small.add(pivot, small.apply(tilt, small.sub(moved_pos, pivot)))
                body_rot = small.mul(tilt, moved_rot)
            local_rot = small.mul_t(body_rot, sole_rot)
            local = within_reach_pose(leg, small.apply_t(body_rot, small.sub(sole, body_pos)), local_rot, REACH_SHARE)
            out[self._leg_servos[side]] = np.subtract(leg_ik_pose(leg, local, local_rot), rows.legs(side, k))
        return out

    def _sole_target(self, side: Side, k: int, contact: SupportName, phase: float, heading: float
                     ) -> tuple[small.Vec3, small.Mat3]:
        """Where the ``side`` sole is to be at gait row ``k`` (position [m], rotation; world): the plan's, a swing
        sole turned by ``heading`` [rad] x ``phase`` about the stance sole and moved against the placement error, a
        landed sole held where it landed."""
        rows = self.rows
        x, y, z, yaw = rows.feet(side, k).tolist()
        sole, sole_rot = (x, y, z), small.rot_z(yaw)
        swinging = contact not in ("double", side)
        if swinging and heading:
            steer = small.rot_z(heading * phase)
            stance = rows.feet(other_side(side), k)[:3].tolist()                   # (the contact: one foot)
            sole, sole_rot = small.add(stance, small.apply(steer, small.sub(sole, stance))), small.mul(steer, sole_rot)
        landed = self._landed(side, k)
        if landed is not None:
            sole, sole_rot = small.add(sole, landed[0]), small.mul(small.rot_z(landed[1]), sole_rot)
        if swinging and self.feedback.placement:
            shift = self.odometry.shift(self.feedback.placement, rows.get("velocity", k)).tolist()
            sole = small.add(sole, small.scaled(shift, phase))
        return sole, sole_rot
