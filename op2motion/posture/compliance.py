"""Where a single-support pose settles on compliant servos: the optimiser's model of the body physics simulates.

An MX-28 at P = 32 is a 12.6 N·m/rad spring (:mod:`op2motion.servo`). Standing on one foot, each pitch joint of the
support leg (ankle, knee, hip, from the floor up) holds the mass above it: it turns by

    theta_j = g / Kp_j * (M x' - sum_{b below j} m_b x_b' - M_above_j x_j')          [rad, small angles]

where ``M x'`` is the whole robot's mass moment, the ``b`` are the support leg's links below the joint (foot, ankle,
shank, thigh; masses from the spec's inertials, placed at their joints' points) and primes are settled positions:
each sag turns everything above its joint, the joints and links above included,

    x_j' = x_j + sum_{i below j} theta_i (z_j - z_i),    M x' = M x + sum_i theta_i (M (z - z_i) - sum_{b below i}
    m_b (z_b - z_i)).

This is linear in (x', theta_1..theta_m): one small system per pose, solved for the whole batch at once, and the
same sideways with the roll joints (ankle, hip). Gravity acts as a negative stiffness against the servos': offsets
between the centre of mass and the joints grow as the pose loads (about threefold on one leg of the OP2), and where
the system's determinant is not positive no equilibrium exists. The torso turns by the sum of the sags. Checked
against MuJoCo's settled centre of mass and tilt on standing one-leg poses (tests/test_posture.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics import BodyPoints
from ..servo import ServoModel
from ..spec import GRAVITY_M_S2, Spec

@dataclass(frozen=True)
class Settled:
    """Predicted settled centre of mass (2, N) [m] in the support frame and the sag-induced torso turn (N,) [rad];
    ``stable`` (N,) is false where the servos are too soft for any equilibrium."""

    com_xy: np.ndarray
    tilt: np.ndarray
    stable: np.ndarray


@dataclass(frozen=True)
class _Joint:
    name: str           # servo joint
    point: str          # body point of its axis
    kp: float           # [N·m/rad]
    below: tuple        # ((mass [kg], points to average, how many chain joints below it move it), ...) of the
                        # support leg's links below this joint


class Compliance:
    """The compliance model of one spec and servo model, prepared once."""

    def __init__(self, spec: Spec, servo: ServoModel | None = None):
        servo = servo or ServoModel.of(spec)
        self.mass = sum(i.mass for i in spec.inertials)
        masses = {i.link: i.mass for i in spec.inertials}
        index = {n: i for i, n in enumerate(spec.joint_names)}
        self.chains: dict[str, tuple[list[_Joint], list[_Joint]]] = {}
        for side in ("left", "right"):
            s = side[0]

            def link(joint: str) -> float:
                return masses.get(spec.joint(f"{s}_{joint}").child, 0.0)

            # The links of the support leg, from the floor up (foot, ankle block, shank, thigh, hip block), lumped at
            # body points; the last number counts the joints of the chain below them (whose sag moves them).
            foot, ankle = (f"{s}_ankle",), (f"{s}_ankle",)
            shank, thigh, hip = (f"{s}_knee", f"{s}_ankle"), (f"{s}_hip", f"{s}_knee"), (f"{s}_hip",)
            kp = lambda j: float(servo.kp[index[f"{s}_{j}"]])  # noqa: E731
            pitch = [_Joint(f"{s}_ank_pitch", f"{s}_ankle", kp("ank_pitch"),
                            ((link("ank_roll"), foot, 0), (link("ank_pitch"), ankle, 0))),
                     _Joint(f"{s}_knee", f"{s}_knee", kp("knee"),
                            ((link("ank_roll"), foot, 0), (link("ank_pitch"), ankle, 0), (link("knee"), shank, 1))),
                     _Joint(f"{s}_hip_pitch", f"{s}_hip", kp("hip_pitch"),
                            ((link("ank_roll"), foot, 0), (link("ank_pitch"), ankle, 0), (link("knee"), shank, 1),
                             (link("hip_pitch"), thigh, 2)))]
            roll = [_Joint(f"{s}_ank_roll", f"{s}_ankle", kp("ank_roll"), ((link("ank_roll"), foot, 0),)),
                    _Joint(f"{s}_hip_roll", f"{s}_hip", kp("hip_roll"),
                           ((link("ank_roll"), foot, 0), (link("ank_pitch"), ankle, 1), (link("knee"), shank, 1),
                            (link("hip_pitch"), thigh, 1), (link("hip_roll"), hip, 1)))]
            self.chains[side] = (pitch, roll)

    def _axis(self, points: BodyPoints, com: np.ndarray, chain: list[_Joint], k: int) -> tuple[np.ndarray, np.ndarray]:
        """Settled coordinate ``k`` (0: x with the pitch joints, 1: y with the roll joints) and the summed sag [rad]:
        the system of the module docstring, unknowns (M x', theta_1..theta_m), for each pose."""
        m, n, mass = len(chain), points.n, self.mass

        def at(names: tuple[str, ...]) -> np.ndarray:
            return np.mean([points.point(p) for p in names], axis=0)          # (N, 3)

        joint_pos = [points.point(j.point) for j in chain]
        system = np.zeros((n, m + 1, m + 1))
        rhs = np.zeros((n, m + 1))
        # M x' - sum_i theta_i (M (z - z_i) - sum_{b below i} m_b (z_b - z_i)) = M x
        system[:, 0, 0] = 1.0
        for i, joint in enumerate(chain):
            lever = mass * (com[2] - joint_pos[i][:, 2])
            for mb, where, _ in joint.below:
                lever -= mb * (at(where)[:, 2] - joint_pos[i][:, 2])
            system[:, 0, 1 + i] = -lever
        rhs[:, 0] = mass * com[k]
        # theta_j Kp_j / g - M x' + sum_b m_b x_b' + M_above x_j' = 0, with x_b', x_j' moved by the sags below them
        for j, joint in enumerate(chain):
            system[:, 1 + j, 1 + j] = joint.kp / GRAVITY_M_S2
            system[:, 1 + j, 0] = -1.0
            above = mass - sum(mb for mb, _, _ in joint.below)
            constant = above * joint_pos[j][:, k]
            for i in range(j):                                        # the joint moves with the sags below it
                system[:, 1 + j, 1 + i] += above * (joint_pos[j][:, 2] - joint_pos[i][:, 2])
            for mb, where, moved_by in joint.below:
                pos = at(where)
                constant = constant + mb * pos[:, k]
                for i in range(moved_by):                             # a lower link moves with the sags below it
                    system[:, 1 + j, 1 + i] += mb * (pos[:, 2] - joint_pos[i][:, 2])
            rhs[:, 1 + j] = -constant
        det = np.linalg.det(system)
        ok = det > 0.0          # the servos outweigh gravity's negative stiffness: a stable equilibrium
        solution = np.linalg.solve(np.where(ok[:, None, None], system, np.eye(m + 1)), rhs[..., None])[..., 0]
        settled = np.where(ok, solution[:, 0] / mass, np.copysign(np.inf, com[k] - joint_pos[0][:, k]))
        return settled, np.where(ok, solution[:, 1:].sum(axis=1), np.inf)

    def settle(self, points: BodyPoints, com: np.ndarray) -> Settled:
        """Where poses standing on ``points.support`` settle, given their centre of mass ``com`` (3, N) [m]."""
        pitch, roll = self.chains[points.support]
        x, pitch_sag = self._axis(points, com, pitch, 0)
        y, roll_sag = self._axis(points, com, roll, 1)
        tilt = np.hypot(pitch_sag, roll_sag)
        return Settled(np.vstack([x, y]), tilt, np.isfinite(tilt))
