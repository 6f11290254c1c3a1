"""Full-body forward kinematics with the book's projection-based (PB) method, batched over N poses.

Book seed 001, eqs. 2.89-2.109 and code 2.12 ``GenMotionsWithPB``: every link is a vector whose sagittal
(x-z) and coronal (y-z) projections follow from the cumulative sagittal angle T and coronal angle F,

    v(T, F, l) = l * (|cos F| cos T, -|sin T| sin F, |cos F| sin T),

chained from the support ankle. The method assumes psi = 0 (no transverse rotation); asking for psi != 0 is a
:class:`ModelError`. Lengths come from the spec geometry, placed as the book places its links:

* the pelvis link joins the two hip roll/pitch points; the torso runs from their midpoint to the torso origin
  (hip-yaw segment plus torso, 0.1222 m on the OP2), with the hip-yaw axes' 5 mm offset behind the origin;
* each arm hangs from the shoulder-roll point of the standing robot (fixed to the torso) with the real upper
  and lower arm. It leaves out what the book's PB leaves out: the shoulder-roll point moving
  with shoulder pitch and the 0.016 m elbow offset, so hands differ from the D-H model by up to a few cm;
* one deliberate fix: the book takes ``abs`` of the pelvis link's sagittal length, which makes the swing hip
  rise whichever way the torso rolls; here it keeps its sign (rigid-body correct, identical for phi1+phi2 on
  the book's side).

The sagittal/coronal projection is exact when either angle is at its neutral value and approximates rigid
rotation otherwise (link lengths shrink by up to a few percent at 20-30° of combined roll and pitch).
"""

from __future__ import annotations

import numpy as np

from op2motion.errors import ModelError
from op2motion.kinematics.batch import run_chunked
from op2motion.kinematics.com import slab_com
from op2motion.kinematics.points import ROW, BodyPoints, fill_support_foot, new_slab
from op2motion.kinematics.trig import sincos
from op2motion.robot.joints import BookAngles
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, other_side

PSI_TOLERANCE_RAD = 1e-12  # psi must be zero for this model


def forward_pb(angles: BookAngles, spec: Spec) -> BodyPoints:
    """Body points of N poses in the support-foot frame; raises :class:`ModelError` when psi != 0."""
    if np.any(np.abs(angles.psi) > PSI_TOLERANCE_RAD):
        raise ModelError("the projection model assumes psi = 0 (no transverse rotation); choose dh", "model")
    out = new_slab(angles.n)
    left = angles.support == "left"
    com = np.empty((3, angles.n))

    def work(a: int, b: int) -> None:
        _chunk(angles.th[a:b], angles.phi[a:b], out[:, :, a:b], spec, left)
        com[:, a:b] = slab_com(out[:, :, a:b], spec)

    run_chunked(angles.n, work)
    return BodyPoints(out, com, angles.support, "pb")


class _Link:
    """A unit projected link vector for one (T, F) pair, and the forward normal of its sagittal direction."""

    __slots__ = ("cx", "sy", "cz", "fx", "fz")

    def __init__(self, t: tuple[np.ndarray, np.ndarray, np.ndarray], f: tuple[np.ndarray, np.ndarray, np.ndarray]):
        sin_t, cos_t, abs_sin_t = t
        sin_f, _, abs_cos_f = f
        self.cx = abs_cos_f * cos_t       # x per unit length
        self.sy = abs_sin_t * sin_f       # -y per unit length
        np.negative(self.sy, out=self.sy)
        self.cz = abs_cos_f * sin_t       # z per unit length
        self.fx, self.fz = -sin_t, cos_t  # sagittal direction turned by +90° (book foot corners)

    def add(self, base: np.ndarray, length: float, out: np.ndarray) -> np.ndarray:
        """``out = base + length * v`` for (3, N) arrays."""
        np.multiply(self.cx, length, out=out[0])
        np.multiply(self.sy, length, out=out[1])
        np.multiply(self.cz, length, out=out[2])
        out += base
        return out


def _chunk(th: np.ndarray, phi: np.ndarray, out: np.ndarray, spec: Spec, left: bool) -> None:
    g = spec.geometry
    m = th.shape[0]
    th, phi = np.ascontiguousarray(th.T), np.ascontiguousarray(phi.T)  # (11, m), (6, m): contiguous rows
    # All 17 cumulative angles of the chunk in one (17, m) array, so one sincos call serves them all.
    a = np.empty((17, m))
    np.copyto(a[0], th[0])
    for i in range(1, 6):                                   # th1, th12, ..., th123456
        np.add(a[i - 1], th[i], out=a[i])
    np.add(a[2], th[6], out=a[6])                        # th1237
    np.add(a[6], th[7], out=a[7])                        # th12378
    np.add(a[2], th[8], out=a[8])                        # th1239
    np.add(a[8], th[9], out=a[9])                        # th123910
    np.add(a[2], th[10], out=a[10])                      # th12311
    np.copyto(a[11], phi[0])
    for i in range(1, 4):                                   # phi1, phi12, phi123, phi1234
        np.add(a[10 + i], phi[i], out=a[11 + i])
    np.add(a[12], phi[4], out=a[15])                     # phi125
    np.add(a[12], phi[5], out=a[16])                     # phi126
    sin_a, cos_a = sincos(a)
    abs_a = np.empty_like(a)
    np.abs(sin_a[:11], out=abs_a[:11])   # |sin T| for the sagittal angles
    np.abs(cos_a[11:], out=abs_a[11:])   # |cos F| for the coronal angles
    trig = [(sin_a[i], cos_a[i], abs_a[i]) for i in range(17)]
    trig_t, arm_t = trig[:6], trig[6:11]
    trig_f, arm_f = trig[11:15], trig[15:17]

    calf, femur = _Link(trig_t[0], trig_f[0]), _Link(trig_t[1], trig_f[0])
    torso = _Link(trig_t[2], trig_f[1])
    thigh, shin, foot = _Link(trig_t[3], trig_f[2]), _Link(trig_t[4], trig_f[2]), _Link(trig_t[5], trig_f[3])
    l_upper, l_lower = _Link(arm_t[0], arm_f[0]), _Link(arm_t[1], arm_f[0])
    r_upper, r_lower = _Link(arm_t[2], arm_f[1]), _Link(arm_t[3], arm_f[1])
    head = _Link(arm_t[4], trig_f[1])

    s, w = ("l", "r") if left else ("r", "l")
    support_side: Side = "left" if left else "right"
    swing_side = other_side(support_side)

    def row(name: str) -> np.ndarray:
        view: np.ndarray = out[ROW[name]]        # (3, N), written in place
        return view

    ankle = row(f"{s}_ankle")
    ankle[0], ankle[1], ankle[2] = 0.0, 0.0, g.ankle_to_sole
    knee = calf.add(ankle, g.calf, row(f"{s}_knee"))
    hip = femur.add(knee, g.thigh, row(f"{s}_hip"))
    # Pelvis link, support hip -> swing hip: the book's l4s = l4 cos(phi12 +/- pi/2) without abs.
    sin12, cos12, abs_cos12 = trig_f[1]
    sin123, cos123, _ = trig_t[2]
    across = -(1.0 if left else -1.0) * 2.0 * g.hip_half_width
    swing_hip = row(f"{w}_hip")
    swing_hip[0] = across * sin12 * cos123
    swing_hip[1] = across * cos12
    swing_hip[2] = across * sin12 * sin123
    swing_hip += hip
    sknee = thigh.add(swing_hip, g.thigh, row(f"{w}_knee"))
    sankle = shin.add(sknee, g.calf, row(f"{w}_ankle"))
    ssole = foot.add(sankle, g.ankle_to_sole, row(f"{swing_side}_sole"))

    centre = 0.5 * (hip + swing_hip)
    torso.add(centre, g.hip_yaw_to_roll, row("pelvis"))
    torso.add(hip, g.hip_yaw_to_roll, row(f"{s}_hip_yaw"))
    torso.add(swing_hip, g.hip_yaw_to_roll, row(f"{w}_hip_yaw"))
    neck = torso.add(centre, g.hip_yaw_to_roll + g.torso, row("neck"))
    forward = -g.hip_x * abs_cos12  # the torso origin lies -hip_x ahead of the hip-yaw axes
    neck[0] += forward * sin123
    neck[2] -= forward * cos123
    torso.add(neck, g.head_pan_height, row("head_pan"))
    tilt = torso.add(neck, g.head_tilt_height, row("head_tilt"))
    head.add(tilt, g.head_length, row("head_top"))
    # Shoulders: lateral unit vector (0, cos phi12, sin phi12) to the left (book p7/p10).
    lat = np.stack([np.zeros_like(cos12), cos12, sin12])
    for side, sign, upper, lower, hand in (("l", 1.0, l_upper, l_lower, "left_hand"),
                                           ("r", -1.0, r_upper, r_lower, "right_hand")):
        np.add(neck, sign * g.shoulder_half_width * lat, out=row(f"{side}_sho_pitch"))
        root = row(f"{side}_sho_roll")
        np.add(neck, sign * (g.shoulder_half_width + g.shoulder_roll_lateral) * lat, out=root)
        root[0] -= g.shoulder_roll_drop * torso.cx
        root[1] -= g.shoulder_roll_drop * torso.sy
        root[2] -= g.shoulder_roll_drop * torso.cz
        elbow = upper.add(root, g.upper_arm, row(f"{side}_el"))
        lower.add(elbow, g.lower_arm, row(hand))

    fill_support_foot(out, spec.foot, support_side)
    for i, (dx, dy) in enumerate(spec.foot.corners(swing_side)):
        corner = out[ROW[f"{swing_side}_foot_{i}"]]
        corner[0] = ssole[0] + dx * foot.fx
        corner[1] = ssole[1] + dy
        corner[2] = ssole[2] + dx * foot.fz
