"""Where a single-support pose settles on compliant servos: the optimiser's model of the body physics simulates.

An MX-28 at P = 32 is a 12.6 N·m/rad spring (:mod:`op2motion.model.servo`). Standing on one foot, each pitch
joint of the support leg (ankle, knee, hip, from the floor up) holds the mass above it: it turns by

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

The swing leg hangs from its hip on the same springs: each of its joints gives by its gravity torque over its
stiffness, theta_j = a_j . ((c_j - o_j) x m_j g) / Kp_j (a_j its axis, o_j its centre, m_j and c_j the mass and
centre of mass of the leg below it), and the swing foot moves by sum_j theta_j a_j x (p - o_j)
(:class:`SwingLegSag`; small angles, each joint on its own, static friction neglected, so it errs towards more sag).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.kinematics import BodyPoints
from op2motion.kinematics.links import attachments
from op2motion.kinematics.points import row_of
from op2motion.model.servo import ServoModel
from op2motion.robot.joints import LEG_JOINTS
from op2motion.robot.spec import GRAVITY_M_S2, Spec
from op2motion.robot.support import Side, Support, other_side


@dataclass(frozen=True)
class Settled:
    """Predicted settled centre of mass (2, N) [m] in the support frame and the sag-induced torso turn (N,) [rad];
    ``stable`` (N,) is false where the servos are too soft for any equilibrium; the sag of each support-leg joint
    [rad], pitch (ankle, knee, hip) and roll (ankle, hip), (joints, N), each turning everything above its axis
    forward / outward (NaN without an equilibrium)."""

    com_xy: np.ndarray
    tilt: np.ndarray
    stable: np.ndarray
    pitch_sag: np.ndarray
    roll_sag: np.ndarray


@dataclass(frozen=True)
class _Joint:
    name: str           # servo joint
    point: str          # body point of its axis
    kp: float           # [N·m/rad]
    # ((mass [kg], points to average, how many chain joints below it move it), ...) of the support leg's links
    # below this joint
    below: tuple[tuple[float, tuple[str, ...], int], ...]


#: One chain's system (:meth:`Compliance._plan`): its body points' rows, s0, sz, rx, and its joints' point rows.
_ChainPlan = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class Compliance:
    """The compliance model of one spec and servo model, prepared once."""

    def __init__(self, spec: Spec, servo: ServoModel | None = None):
        servo = servo or ServoModel.of(spec)
        self.mass = sum(i.mass for i in spec.inertials)
        masses = {i.link: i.mass for i in spec.inertials}
        index = {n: i for i, n in enumerate(spec.joint_names)}
        self.chains: dict[str, tuple[_ChainPlan, _ChainPlan]] = {}     # side -> (pitch, roll)
        for side in ("left", "right"):
            s = side[0]

            def link(joint: str) -> float:
                return masses.get(spec.joint(f"{s}_{joint}").child, 0.0)

            # The links of the support leg, from the floor up (foot, ankle block, shank, thigh, hip block), lumped at
            # body points; the last number counts the joints of the chain below them (whose sag moves them).
            foot, ankle = (f"{s}_ankle",), (f"{s}_ankle",)
            shank, thigh, hip = (f"{s}_knee", f"{s}_ankle"), (f"{s}_hip", f"{s}_knee"), (f"{s}_hip",)

            def kp(j: str) -> float:
                return float(servo.kp[index[f"{s}_{j}"]])

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
            self.chains[side] = (self._plan(pitch), self._plan(roll))

    def _plan(self, chain: list[_Joint]) -> _ChainPlan:
        """The system of the module docstring as constant tensors: with v = the coordinates [z or x] of the chain's
        body points followed by the centre of mass, system = s0 + v_z . sz and rhs = v_x . rx (both linear)."""
        names = sorted({p for j in chain for _, where, _ in j.below for p in where} | {j.point for j in chain})
        col = {name: i for i, name in enumerate(names)}
        com = len(names)
        m = len(chain)
        s0 = np.zeros((m + 1, m + 1))
        sz = np.zeros((len(names) + 1, m + 1, m + 1))       # coefficient of each z coordinate in each entry
        rx = np.zeros((len(names) + 1, m + 1))               # coefficient of each x coordinate in each rhs entry

        def add_at(target: np.ndarray, where: tuple[str, ...], weight: float) -> None:   # an averaged point
            for name in where:
                target[col[name]] += weight / len(where)

        s0[0, 0] = 1.0                                        # M x' - sum_i theta_i lever_i = M x
        rx[com, 0] = self.mass
        for i, joint in enumerate(chain):
            sz[com, 0, 1 + i] -= self.mass                    # lever_i = M (z - z_i) - sum_b m_b (z_b - z_i)
            sz[col[joint.point], 0, 1 + i] += self.mass
            for mb, where, _ in joint.below:
                add_at(sz[:, 0, 1 + i], where, mb)
                sz[col[joint.point], 0, 1 + i] -= mb
        for j, joint in enumerate(chain):                     # theta_j Kp_j / g - M x' + ... = -(...)
            s0[1 + j, 1 + j] = joint.kp / GRAVITY_M_S2
            s0[1 + j, 0] = -1.0
            above = self.mass - sum(mb for mb, _, _ in joint.below)
            rx[col[joint.point], 1 + j] -= above
            for i in range(j):                                # the joint moves with the sags below it
                sz[col[joint.point], 1 + j, 1 + i] += above
                sz[col[chain[i].point], 1 + j, 1 + i] -= above
            for mb, where, moved_by in joint.below:
                add_at(rx[:, 1 + j], where, -mb)
                for i in range(moved_by):                     # a lower link moves with the sags below it
                    add_at(sz[:, 1 + j, 1 + i], where, mb)
                    sz[col[chain[i].point], 1 + j, 1 + i] -= mb
        return np.array([row_of(n) for n in names]), s0, sz, rx, np.array([row_of(j.point) for j in chain])

    def _system(self, points: BodyPoints, com: np.ndarray, plan: _ChainPlan, k: int,
                size: int) -> tuple[np.ndarray, np.ndarray]:
        """The system of one chain for every pose, padded to ``size`` unknowns (an identity on the extra ones)."""
        rows, s0, sz, rx, _ = plan
        coords = points.data[rows]                                            # (points, 3, N)
        z = np.concatenate([coords[:, 2], com[2][None]]).T                    # (N, points + 1)
        x = np.concatenate([coords[:, k], com[k][None]]).T
        system = np.zeros((points.n, size, size))
        m = len(s0)
        system[:, :m, :m] = s0 + np.einsum("nk,kij->nij", z, sz)
        system[:, m:, m:] = np.eye(size - m)
        rhs = np.zeros((points.n, size))
        rhs[:, :m] = x @ rx
        return system, rhs

    def settle(self, points: BodyPoints, com: np.ndarray) -> Settled:
        """Where poses standing on ``points.support`` settle, given their centre of mass ``com`` (3, N) [m]: the
        pitch (x) and roll (y) systems solved together, unknowns (M x', theta_1..theta_m) each."""
        pitch, roll = self.chains[points.support]
        size = max(len(pitch[1]), len(roll[1]))
        sp, rp = self._system(points, com, pitch, 0, size)
        sr, rr = self._system(points, com, roll, 1, size)
        system, rhs = np.concatenate([sp, sr]), np.concatenate([rp, rr])
        ok = np.linalg.det(system) > 0.0    # the servos outweigh gravity's negative stiffness: a stable equilibrium
        solution = np.linalg.solve(np.where(ok[:, None, None], system, np.eye(size)), rhs[..., None])[..., 0]
        n = points.n
        settled = np.where(ok, solution[:, 0] / self.mass, np.inf)
        sag = np.where(ok, solution[:, 1:].sum(axis=1), np.inf)
        xy = np.vstack([settled[:n], settled[n:]])
        xy = np.where(np.isfinite(xy), xy, np.copysign(np.inf, com[:2] - points.point(pitch_root(points))[:, :2].T))
        tilt = np.hypot(sag[:n], sag[n:])
        each = np.where(ok[:, None], solution[:, 1:], np.nan)
        return Settled(xy, tilt, np.isfinite(tilt), each[:n, :len(pitch[4])].T, each[n:, :len(roll[4])].T)

    def settled_heights(self, points: BodyPoints, settled: Settled, xyz: np.ndarray) -> np.ndarray:
        """Heights [m] (k, N) after the sags of points ``xyz`` (k, 3, N) above the support leg (e.g. the swing foot's
        corners): each sag turns them about its joint's axis, so z drops by the sag times the lever in x (pitch)
        or y (roll). NaN where no equilibrium exists."""
        pitch, roll = self.chains[points.support]
        z = xyz[:, 2].copy()
        for (_, _, _, _, axes), sag, k in ((pitch, settled.pitch_sag, 0), (roll, settled.roll_sag, 1)):
            for axis_row, theta in zip(axes, sag):
                z -= theta * (xyz[:, k] - points.data[axis_row, k])
        return z


def pitch_root(points: BodyPoints) -> str:
    """The support ankle's body point (where an unstable pose falls away from)."""
    return f"{points.support[0]}_ankle"




class SwingLegSag:
    """How far the swing leg's own weight lowers its foot on compliant servos, for one spec, support and servo
    model; evaluated on the D-H chain's frames (:func:`op2motion.kinematics.dh_chain.matrix_frames`)."""

    def __init__(self, spec: Spec, support: Support | Side, servo: ServoModel | None = None):
        servo = servo or ServoModel.of(spec)
        attached = attachments(spec, support)
        side = other_side(support)[0]
        joints = [spec.joint(f"{side}_{name}") for name in LEG_JOINTS]
        inertial = {i.link: i for i in spec.inertials}
        index = {n: i for i, n in enumerate(spec.joint_names)}
        self.slots = np.array([attached[j.child].slot for j in joints])
        self.local = np.array([attached[j.child].local for j in joints])            # (J, 4, 4) joint frames
        self.axes = np.array([j.axis for j in joints], dtype=float)                 # in the child link frames
        self.kp = np.array([servo.kp[index[j.name]] for j in joints])
        # each link of the leg below the hip: its slot, local CoM [m] and mass [kg]; joint j carries links j..end
        links = [j.child for j in joints]
        self.link_slots = np.array([attached[link].slot for link in links])
        self.link_com = np.array([attached[link].local[:3, :3] @ np.asarray(inertial[link].link_com)
                                  + attached[link].local[:3, 3] if link in inertial else np.zeros(3)
                                  for link in links])
        self.link_mass = np.array([inertial[link].mass if link in inertial else 0.0 for link in links])

    def heights(self, frames: np.ndarray, xyz: np.ndarray) -> np.ndarray:
        """Height change [m] (k, N) of points ``xyz`` (k, 3, N) on the swing foot, for chain frames
        (slots, N, 4, 4)."""
        joint = frames[self.slots] @ self.local[:, None]                             # (J, N, 4, 4)
        origin = joint[..., :3, 3]                                                   # (J, N, 3)
        axis = np.einsum("jnab,jb->jna", joint[..., :3, :3], self.axes)               # (J, N, 3) world axes
        f = frames[self.link_slots]
        com = np.einsum("jnab,jb->jna", f[..., :3, :3], self.link_com) + f[..., :3, 3]
        moment = np.cumsum((self.link_mass[:, None, None] * com)[::-1], axis=0)[::-1]  # links j..end: sum m c
        mass = np.cumsum(self.link_mass[::-1])[::-1]
        lever = moment - mass[:, None, None] * origin                                # m_j (c_j - o_j)
        # gravity torque about each axis: a . (lever x (0, 0, -g)) = -g (a_x lever_y - a_y lever_x)
        torque = -GRAVITY_M_S2 * (axis[..., 0] * lever[..., 1] - axis[..., 1] * lever[..., 0])
        theta = torque / self.kp[:, None]                                            # (J, N)
        rel = xyz.transpose(0, 2, 1)[None] - origin[:, None]                         # (J, k, N, 3)
        # z of a x rel = a_x rel_y - a_y rel_x
        dz = axis[:, None, :, 0] * rel[..., 1] - axis[:, None, :, 1] * rel[..., 0]
        drop: np.ndarray = np.einsum("jn,jkn->kn", theta, dz)
        return drop

