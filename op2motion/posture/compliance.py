"""Where a single-support pose settles on compliant servos: the optimiser's model of the body physics simulates.

An MX-28 at P = 32 is a 12.6 N·m/rad spring (:mod:`op2motion.servo`). Standing on one foot, each pitch joint of
the support leg (ankle, knee, hip) carries about the robot's weight ``W`` at the horizontal distance between the
joint and the centre of mass, so it sags by ``theta_j = W (x - x_j) / Kp_j``, which turns everything above it and
moves the centre of mass by ``theta_j (z - z_j)``. At equilibrium (small angles, for the whole batch at once):

    x_settled = x + sum_j (W / Kp_j) (z - z_j) (x_settled - x_j)
              = (x - B) / (1 - A),   A = sum_j (W / Kp_j) (z - z_j),   B = sum_j (W / Kp_j) (z - z_j) x_j,

and the same sideways with the roll joints (ankle, hip). ``A`` is the gravity's "negative stiffness" against the
servos': near 0.7 on one leg of the OP2, so offsets between the centre of mass and the joints grow about threefold
as the pose loads, and at ``A >= 1`` no equilibrium exists. The torso turns by the sum of the sags. Checked
against MuJoCo's settled centre of mass on PSO poses: within a few millimetres where the pose stands.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics import BodyPoints
from ..servo import ServoModel
from ..spec import GRAVITY_M_S2, Spec

PITCH_JOINTS = ("ank_pitch", "knee", "hip_pitch")
ROLL_JOINTS = ("ank_roll", "hip_roll")


@dataclass(frozen=True)
class Settled:
    """Predicted settled centre of mass (2, N) [m] in the support frame and the sag-induced torso turn (N,) [rad];
    ``stable`` (N,) is false where the servos are too soft for any equilibrium."""

    com_xy: np.ndarray
    tilt: np.ndarray
    stable: np.ndarray


class Compliance:
    """The compliance model of one spec and servo model, prepared once."""

    def __init__(self, spec: Spec, servo: ServoModel | None = None):
        servo = servo or ServoModel.of(spec)
        self.weight = sum(i.mass for i in spec.inertials) * GRAVITY_M_S2
        index = {n: i for i, n in enumerate(spec.joint_names)}
        self.pitch = {side: [(f"{side[0]}_{j}", servo.kp[index[f"{side[0]}_{j}"]]) for j in PITCH_JOINTS]
                      for side in ("left", "right")}
        self.roll = {side: [(f"{side[0]}_{j}", servo.kp[index[f"{side[0]}_{j}"]]) for j in ROLL_JOINTS]
                     for side in ("left", "right")}

    def _axis(self, points: BodyPoints, com: np.ndarray, joints: list, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Settled coordinate ``k`` (0: x with pitch joints, 1: y with roll joints) and the summed sag [rad]."""
        a = np.zeros(points.n)
        b = np.zeros(points.n)
        for name, kp in joints:
            p = points.point(name)
            lever = self.weight / kp * (com[2] - p[:, 2])
            a += lever
            b += lever * p[:, k]
        ok = a < 1.0
        settled = np.where(ok, (com[k] - b) / np.where(ok, 1.0 - a, 1.0), np.copysign(np.inf, com[k]))
        sag = sum(self.weight / kp * (settled - points.point(name)[:, k]) for name, kp in joints)
        return settled, np.where(ok, sag, np.inf)

    def settle(self, points: BodyPoints, com: np.ndarray) -> Settled:
        """Where poses standing on ``points.support`` settle, given their centre of mass ``com`` (3, N) [m]."""
        x, pitch = self._axis(points, com, self.pitch[points.support], 0)
        y, roll = self._axis(points, com, self.roll[points.support], 1)
        tilt = np.hypot(pitch, roll)
        return Settled(np.vstack([x, y]), tilt, np.isfinite(tilt))
