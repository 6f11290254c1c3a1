"""The swing foot's own attitude: level in the world however the torso tilts, and its toe raised over the floor.

Three preset keys (:mod:`.params`), all off by default (the plan's swing foot, carried with the torso's attitude):

* ``swing_level`` and ``swing_level_roll`` (shares, 0–1): the swing leg's goals are solved for the torso turned by
  these shares of its measured attitude error (pitch, roll; about the support point) on top of the stabiliser's
  turn, so the swing sole stays where the plan puts it in the world, level and at its height, instead of following
  a torso that pitches forward (its toe then points down: on servos at 0.6 of the model's stiffness, a torso pitched
  3-5° forward caught the swing toe on the floor half way through the swing and the body tripped);
* ``swing_toe_deg`` [deg]: the swing sole's toe raised by this angle at mid swing (``sin(pi phase)``: level at lift-off
  and landing), turned about its heel's edge so that the heel keeps its height.
"""

from __future__ import annotations

import math
from typing import Sequence

from op2motion.kinematics import small


def toe_raised(sole: Sequence[float], sole_rot: Sequence[Sequence[float]], phase: float, toe_rad: float,
               back_m: float) -> tuple[small.Vec3, small.Mat3]:
    """The swing sole (position (3,) [m], rotation (3, 3); as tuples, :mod:`~op2motion.kinematics.small`: the
    controller calls it every tick) with its toe raised by ``toe_rad`` [rad] x ``sin(pi phase)`` about its heel
    edge, ``back_m`` [m] behind the sole centre (world frame)."""
    angle = toe_rad * math.sin(math.pi * min(max(float(phase), 0.0), 1.0))
    if not angle:
        return small.vec(sole), small.mat(sole_rot)
    tilt = small.rot_y(-angle)                                    # about the sole's y: toe up
    heel = small.add(sole, small.apply(sole_rot, (-back_m, 0.0, 0.0)))
    turned = small.mul(sole_rot, tilt)
    return small.add(heel, small.apply(turned, (back_m, 0.0, 0.0))), turned
