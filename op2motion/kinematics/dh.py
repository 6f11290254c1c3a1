"""Full-body forward kinematics with the Denavit-Hartenberg method, batched over N poses.

The chain and frame numbering follow the book (seed 001, code 2.5 ``GenMotionsWithDH``, tables 2.3-2.5): frame 0
on the support ankle, B1-B6 up the support leg to the swing hip, B7-B12 down the swing leg to its sole, frames 13-16
(left arm), 17-20 (right arm) and 21-23 (neck, head) hung from frame 6 by the book's additional transforms. Both
support feet and the transverse angles psi are supported. Lengths are the real robot's (spec geometry), and the
chain adds the fixed transforms the book leaves out: the hip-yaw axes 5 mm behind the torso origin and the
0.016 m forward elbow offset; the shoulder-roll offset is 0.0245 m (book 0.024). With these the joint centres
coincide with the official ROBOTIS description for the servo angles of :func:`op2motion.joints.book_to_servo`.
"""

from __future__ import annotations

import math

import numpy as np

from ..joints import BookAngles
from ..spec import Spec
from ..trig import sincos
from .batch import run_chunked
from .com import slab_com
from .frames import Frame
from .points import ROW, BodyPoints, foot_corner_offsets, new_slab

_HALF_PI = math.pi / 2
# World axes of frame 0 (book W with gamma = 0): x0 = +Y, y0 = +Z, z0 = +X.
_W0 = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
# Book eq. 2.58: the additional transform that turns the hip-roll DH frame into the hip-yaw frame.
_HIP = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
# Book T13_6/T17_6 (shoulders) and T21_6 (neck) rotations, for left and right support.
_ARM_ROT = {True: ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
            False: ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0))}
_NECK_ROT = {True: ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
             False: ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))}


def forward_dh(angles: BookAngles, spec: Spec) -> BodyPoints:
    """Body points of N poses in the support-foot frame (sole centre at the origin, gamma = 0)."""
    out = new_slab(angles.n)
    left = angles.support == "left"
    com = np.empty((3, angles.n))

    def work(a: int, b: int) -> None:
        _chunk(angles.th[a:b], angles.phi[a:b], angles.psi[a:b], out[:, :, a:b], spec, left)
        com[:, a:b] = slab_com(out[:, :, a:b], spec)

    run_chunked(angles.n, work)
    return BodyPoints(out, com, angles.support, "dh")


def chain_frames(angles: BookAngles, spec: Spec) -> dict[str, Frame]:
    """All book frames (``"0"``..``"23"``, plus ``"15e"``/``"19e"`` at the elbows) for a small batch."""
    frames: dict[str, Frame] = {}
    _chunk(angles.th, angles.phi, angles.psi, new_slab(angles.n), spec, angles.support == "left", frames)
    return frames


def _chunk(th: np.ndarray, phi: np.ndarray, psi: np.ndarray, out: np.ndarray, spec: Spec, left: bool,
           keep: dict[str, Frame] | None = None) -> None:
    g = spec.geometry
    m = th.shape[0]
    sin_a, cos_a = sincos(np.concatenate([th, phi, psi], axis=1).T)  # one call for all 20 angles
    pairs = [(sin_a[i], cos_a[i]) for i in range(20)]
    st, sf, sy = pairs[:11], pairs[11:17], pairs[17:]                    # (sin, cos) of th, phi, psi
    sgn = 1.0 if left else -1.0

    # Support leg, from the ankle up (B1-B6). Shifted angles use cos/sin identities instead of new trig.
    f0 = Frame.constant(_W0, (0.0, 0.0, g.ankle_to_sole), m)
    f1 = f0.dh(-sf[0][0], sf[0][1], 0.0, 0.0, _HALF_PI)                     # delta = phi1 + pi/2
    f2 = f1.dh(st[0][0], st[0][1], 0.0, g.calf, 0.0)                        # delta = -th1 + pi/2
    f3 = f2.dh(st[1][1], -st[1][0], 0.0, g.thigh, 0.0)                      # delta = -th2
    f4 = f3.dh(st[2][1], -st[2][0], 0.0, 0.0, -_HALF_PI)                    # delta = -th3
    f5 = f4.dh(sf[1][1], sf[1][0], 0.0, g.hip_yaw_to_roll, 0.0).fixed(_HIP)  # delta = phi2
    f6 = f5.dh(sgn * sy[0][1], sgn * sy[0][0], 0.0, 2.0 * g.hip_half_width, 0.0)  # psi1 (+pi on right support)
    # Swing leg, from the hip yaw down (B7-B12).
    f7 = f6.dh(sy[1][1], sy[1][0], 0.0, 0.0, -sgn * _HALF_PI).fixed(None, (0.0, sgn * g.hip_yaw_to_roll, 0.0))
    f8 = f7.dh(sgn * sf[2][0], -sgn * sf[2][1], 0.0, 0.0, -_HALF_PI)        # delta = phi3 -/+ pi/2
    f9 = f8.dh(-st[3][1], st[3][0], 0.0, g.thigh, 0.0)                      # delta = -th4 + pi
    f10 = f9.dh(st[4][1], -st[4][0], 0.0, g.calf, 0.0)                      # delta = -th5
    f11 = f10.dh(st[5][1], -st[5][0], 0.0, 0.0, _HALF_PI)                   # delta = -th6
    f12 = f11.dh(sf[3][1], sf[3][0], 0.0, g.ankle_to_sole, 0.0)             # delta = phi4
    # Upper body hung from frame 6; the torso origin sits -hip_x forward of the hip-yaw axes.
    hw, sh, fwd = g.hip_half_width, g.shoulder_half_width, -g.hip_x * sgn
    f13 = f6.fixed(_ARM_ROT[left], (-hw - sgn * sh, fwd, g.torso))
    f17 = f6.fixed(_ARM_ROT[left], (-hw + sgn * sh, fwd, g.torso))
    f21 = f6.fixed(_NECK_ROT[left], (-hw, fwd, g.torso))
    arms = {}
    for first, base, t_pitch, s_roll, t_elbow, lateral in ((13, f13, 6, 4, 7, 1.0), (17, f17, 8, 5, 9, -1.0)):
        fa = base.dh(st[t_pitch][1], -st[t_pitch][0], lateral * g.shoulder_roll_lateral, g.shoulder_roll_drop,
                     _HALF_PI)                                              # delta = -th7 / -th9
        fb = fa.dh(-sf[s_roll][1], -sf[s_roll][0], 0.0, g.upper_arm, -_HALF_PI)  # delta = phi5 - pi / phi6 - pi
        fe = fb.fixed(None, (0.0, -g.elbow_forward, 0.0))                   # the real elbow offset
        fh = fe.dh(st[t_elbow][1], -st[t_elbow][0], 0.0, g.lower_arm, 0.0)  # delta = -th8 / -th10
        arms[first] = (base, fa, fb, fe, fh)
    f22 = f21.dh(sy[2][1], sy[2][0], g.head_tilt_height, 0.0, _HALF_PI)     # delta = psi3
    f23 = f22.dh(st[10][0], st[10][1], 0.0, g.head_length, 0.0)             # delta = -th11 + pi/2

    s, w = ("l", "r") if left else ("r", "l")
    rows = {
        f"{s}_ankle": f0.p, f"{s}_knee": f2.p, f"{s}_hip": f3.p, f"{s}_hip_yaw": f5.p,
        f"{w}_hip_yaw": f6.p, f"{w}_hip": f7.p, f"{w}_knee": f9.p, f"{w}_ankle": f10.p,
        "neck": f21.p, "head_pan": f21.point((0.0, 0.0, g.head_pan_height)), "head_tilt": f22.p, "head_top": f23.p,
        "l_sho_pitch": arms[13][0].p, "l_sho_roll": arms[13][1].p, "l_el": arms[13][3].p, "left_hand": arms[13][4].p,
        "r_sho_pitch": arms[17][0].p, "r_sho_roll": arms[17][1].p, "r_el": arms[17][3].p, "right_hand": arms[17][4].p,
    }
    for name, value in rows.items():
        out[ROW[name]] = value
    np.add(f5.p, f6.p, out=out[ROW["pelvis"]])
    out[ROW["pelvis"]] *= 0.5
    support_side, swing_side = ("left", "right") if left else ("right", "left")
    out[ROW[f"{support_side}_sole"]] = 0.0
    out[ROW[f"{swing_side}_sole"]] = f12.p
    for i, (dx, dy) in enumerate(foot_corner_offsets(spec.foot, support_side)):
        out[ROW[f"{support_side}_foot_{i}"]] = np.array([dx, dy, 0.0])[:, None]
    for i, (dx, dy) in enumerate(foot_corner_offsets(spec.foot, swing_side)):
        out[ROW[f"{swing_side}_foot_{i}"]] = f12.point((0.0, dy, dx))    # frame 12: y left, z forward
    if keep is not None:
        keep.update({str(i): f for i, f in enumerate((f0, f1, f2, f3, f4, f5, f6, f7, f8, f9, f10, f11, f12))})
        for first, (base, fa, fb, fe, fh) in arms.items():
            keep.update({str(first): base, str(first + 1): fa, str(first + 2): fb, f"{first + 2}e": fe,
                         str(first + 3): fh})
        keep.update({"21": f21, "22": f22, "23": f23})
