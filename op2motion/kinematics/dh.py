"""Full-body forward kinematics with the Denavit-Hartenberg method, batched over N poses.

The chain and frame numbering follow the book (seed 001, code 2.5 ``GenMotionsWithDH``, tables 2.3-2.5): frame 0
on the support ankle, B1-B6 up the support leg to the swing hip, B7-B12 down the swing leg to its sole, frames 13-16
(left arm), 17-20 (right arm) and 21-23 (neck, head) hung from frame 6 by the book's additional transforms. Both
support feet and the transverse angles psi are supported. Lengths are the real robot's (spec geometry), and the
chain adds the fixed transforms the book leaves out: the hip-yaw axes 5 mm behind the torso origin and the
0.016 m forward elbow offset; the shoulder-roll offset is 0.0245 m (book 0.024). With these the joint centres
coincide with the official ROBOTIS description for the servo angles of :func:`op2motion.robot.joints.book_to_servo`.

The chain is one table (:func:`chain`). Two evaluators read it: column arithmetic for large batches (few, long
NumPy calls; chunked on all cores) and 4x4 matrix products for small ones such as a PSO swarm, where the number of
NumPy calls, not arithmetic, sets the time.
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.kinematics.batch import run_chunked
from op2motion.kinematics.com import slab_com
from op2motion.kinematics.dh_chain import W0, chain, chain_points, matrix_frames, matrix_plan, point_layout
from op2motion.kinematics.frames import Frame
from op2motion.kinematics.links import full_com_plan
from op2motion.kinematics.points import ROW, BodyPoints, fill_support_foot, new_slab
from op2motion.kinematics.trig import sincos
from op2motion.robot.joints import BookAngles
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support

MATRIX_BELOW = 64  # batches smaller than this (a PSO swarm) use the 4x4 matrix evaluator
_HALF_PI = math.pi / 2


def _shifted(c: np.ndarray, s: np.ndarray, sign: float, offset: float) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of sign·q + offset from cos q, sin q (offset a multiple of pi/2: swaps and signs only)."""
    quarter = round(offset / _HALF_PI) % 4
    s = s if sign > 0 else -s
    return ((c, s), (-s, c), (-c, -s), (s, -c))[quarter]


def _columns(q: np.ndarray, out: np.ndarray, spec: Spec, support: Support | Side,
             full_com: np.ndarray | None = None) -> None:
    """Column evaluator: q is (m, 20) [rad]; fills out (rows, 3, m) and, if given, the full CoM (3, m)."""
    m = q.shape[0]
    sin_q, cos_q = sincos(np.ascontiguousarray(q.T))
    frames = {"0": Frame.constant(W0, (0.0, 0.0, spec.geometry.ankle_to_sole), m)}
    for st in chain(spec, support):
        f = frames[st.parent]
        if st.var is not None:
            c, s = _shifted(cos_q[st.var], sin_q[st.var], st.sign, st.offset)
            f = f.dh(c, s, st.d, st.a, st.alpha)
        if st.trans is not None or st.rot is not None:
            f = f.fixed(st.rot, st.trans or (0.0, 0.0, 0.0))
        frames[st.frame] = f
    for row, frame, local in chain_points(spec, support):
        out[ROW[row]] = frames[frame].point(local)
    np.add(frames["5"].p, frames["6"].p, out=out[ROW["pelvis"]])
    out[ROW["pelvis"]] *= 0.5
    fill_support_foot(out, spec.foot, support)
    if full_com is not None:
        plan = full_com_plan(spec, support)
        full_com[:] = 0.0
        for name, mass, weighted in zip(plan.frames, plan.masses, plan.weighted):   # sum of M_f (o_f + R_f c_f)
            f = frames[name]
            full_com += mass * f.p
            for col, w in zip((f.x, f.y, f.z), weighted):
                full_com += w * col
        full_com /= plan.total


def _matrices(q: np.ndarray, out: np.ndarray, spec: Spec, support: Support | Side,
              full_com: np.ndarray | None = None, frames: np.ndarray | None = None) -> None:
    """4x4 matrix evaluator for small batches; fills out (rows, 3, m) like :func:`_columns` (from the chain
    ``frames`` if already known)."""
    plan = matrix_plan(spec, support)
    frames = matrix_frames(q, spec, support) if frames is None else frames
    _, origin_rows, origin_frames, offset_rows, offset_frames, offsets = point_layout(spec, support)
    out[origin_rows] = frames[origin_frames, :, :3, 3].transpose(0, 2, 1)
    rot = frames[offset_frames, :, :3, :3]
    out[offset_rows] = np.einsum("fmij,fj->fim", rot, offsets) + frames[offset_frames, :, :3, 3].transpose(0, 2, 1)
    five, six = plan.slots["5"], plan.slots["6"]
    out[ROW["pelvis"]] = 0.5 * (frames[five, :, :3, 3] + frames[six, :, :3, 3]).T
    fill_support_foot(out, spec.foot, support)
    if full_com is not None:
        com = full_com_plan(spec, support)
        picked = frames[com.slots]                                         # (F, m, 4, 4)
        homogeneous = np.concatenate([com.weighted, com.masses[:, None]], axis=1)   # (F, 4): [M c, M]
        total = (picked[:, :, :3, :] @ homogeneous[:, None, :, None])[..., 0].sum(axis=0)   # (m, 3)
        full_com[:] = total.T / com.total


def forward_dh(angles: BookAngles, spec: Spec, full_com: bool = False) -> BodyPoints:
    """Body points of N poses in the support-foot frame (sole centre at the origin, gamma = 0), the lumped CoM
    and, with ``full_com``, the full-inertia CoM."""
    n, support = angles.n, angles.support
    out, com = new_slab(n), np.empty((3, n))
    full = np.empty((3, n)) if full_com else None
    q = angles.vector()
    evaluate = _matrices if n < MATRIX_BELOW else _columns

    def work(a: int, b: int) -> None:
        evaluate(q[a:b], out[:, :, a:b], spec, support, None if full is None else full[:, a:b])
        com[:, a:b] = slab_com(out[:, :, a:b], spec)

    run_chunked(n, work)
    return BodyPoints(out, com, support, "dh", full)


def forward_dh_frames(angles: BookAngles, spec: Spec, full_com: bool = False) -> tuple[BodyPoints, np.ndarray]:
    """:func:`forward_dh` for a swarm-sized batch, with the chain frames (slots, N, 4, 4) it was computed from
    (for the link shapes and joint axes, :mod:`.links`)."""
    n, support = angles.n, angles.support
    q = angles.vector()
    frames = matrix_frames(q, spec, support)
    out = new_slab(n)
    full = np.empty((3, n)) if full_com else None
    _matrices(q, out, spec, support, full, frames)
    return BodyPoints(out, slab_com(out, spec), support, "dh", full), frames
