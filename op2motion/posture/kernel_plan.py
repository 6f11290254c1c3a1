"""The posture cost's constants as flat arrays, for the compiled swarm kernel (:mod:`.kernel`).

Everything here is read off the plans the NumPy evaluators already build (the D-H chain's matrix plan and point
layout, the link inertials' full-CoM plan, the compliance systems, the swing leg's sag, the collision shapes), so
the kernel and :class:`~op2motion.posture.cost.CostModel` share one description of the body; only the layout
differs (padded arrays instead of Python objects). Built once per problem.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from op2motion.kinematics.com import mass_weights
from op2motion.kinematics.dh_chain import matrix_plan, point_layout
from op2motion.kinematics.links import full_com_plan
from op2motion.kinematics.points import ALL_ROWS, ROW, row_of
from op2motion.kinematics.shapes import BOX_CORNERS, BOX_EDGES, ROUNDS, SEGMENT_GRID, shape_set
from op2motion.model.compliance import Compliance, SwingLegSag
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support, as_side, other_side

CONST_NAMES = ("penalty", "w_violation", "w_margin", "margin_cap_m", "w_upright", "sag_tilt_limit_rad",
               "self_clearance_m", "lifted_m", "floor_tolerance_m", "gravity_m_s2")
UNKNOWNS = 4          # the larger compliance system (pitch: M x' and three sags)


class KernelPlan(NamedTuple):
    """Constants of one posture problem in the kernel's layout (lengths [m], masses [kg], stiffness [N·m/rad])."""

    # the D-H chain: slot s > 0 is parent[s] · local(s); local from a joint (index >= 0) or a fixed transform
    parent: np.ndarray          # (S,) int
    slot_joint: np.ndarray      # (S,) int, -1 where fixed
    slot_fixed: np.ndarray      # (S,) int, -1 where a joint
    var: np.ndarray             # (J,) int: book-variable index of each joint
    sign: np.ndarray            # (J,)
    offset: np.ndarray          # (J,)
    basis: np.ndarray           # (J, 3, 16)
    fixed_local: np.ndarray     # (F, 4, 4)
    root: np.ndarray            # (4, 4)
    # body points: row r = frame row_slot[r] · row_point[r]; -1 slots are the constant rows (support foot)
    row_slot: np.ndarray        # (R,) int
    row_point: np.ndarray       # (R, 3)
    const_rows: np.ndarray      # (R, 3): the support sole and corners
    pelvis: np.ndarray          # (3,) int: pelvis row, its two chain slots
    lumped: np.ndarray          # (R,) mass fractions of the lumped CoM
    # the full-inertia CoM
    com_slots: np.ndarray       # (K,) int
    com_mass: np.ndarray        # (K,)
    com_weighted: np.ndarray    # (K, 3)
    total_mass: float
    # compliance systems, pitch (0) and roll (1); name rows padded with -1, the CoM's coefficients last
    ch_rows: np.ndarray         # (2, N) int
    ch_size: np.ndarray         # (2,) int: unknowns of each system
    ch_s0: np.ndarray           # (2, U, U)
    ch_sz: np.ndarray           # (2, N + 1, U, U)
    ch_rx: np.ndarray           # (2, N + 1, U)
    ch_axis_rows: np.ndarray    # (2, U - 1) int, -1 padded
    # the swing leg's sag
    sw_slots: np.ndarray        # (L,) int
    sw_local: np.ndarray        # (L, 4, 4)
    sw_axes: np.ndarray         # (L, 3)
    sw_kp: np.ndarray           # (L,)
    sw_link_slots: np.ndarray   # (L,) int
    sw_link_com: np.ndarray     # (L, 3)
    sw_link_mass: np.ndarray    # (L,)
    # collision shapes and pairs
    sh_slots: np.ndarray        # (H,) int
    sh_local: np.ndarray        # (H, 4, 4)
    sh_box: np.ndarray          # (H,) bool
    sh_half: np.ndarray         # (H, 3)
    sh_reach: np.ndarray        # (H,): half length of a segment along its z
    sh_radius: np.ndarray       # (H,)
    sh_bound: np.ndarray        # (H,)
    pairs: np.ndarray           # (P, 2) int
    # the problem
    hand_row: int
    ankle_row: int              # the support ankle (where a pose without equilibrium falls away from)
    swing_first: int            # first swing-foot corner row
    torso_rows: np.ndarray      # (4,) int: neck, pelvis, l_sho_pitch, r_sho_pitch
    torso_ab: np.ndarray        # (2,): the pelvis direction in the torso frame, u = a x + b z
    target: np.ndarray          # (3,)
    extents: np.ndarray         # (4,): front, back, left, right
    full: bool                  # full-inertia CoM on compliant servos (else the book's lumped rigid body)
    # the cost's weights and thresholds (passed, not compiled in: a cached kernel never sees stale values)
    consts: np.ndarray          # (CONSTS,) in the order of :data:`CONST_NAMES`
    # the clearance search: box corner signs (8, 3), box edges (12, 2), samples along a segment, rounds
    box_corners: np.ndarray
    box_edges: np.ndarray
    grid: np.ndarray
    rounds: int


def _chains(compliance: Compliance, support: Support | Side) -> tuple[np.ndarray, ...]:
    plans = compliance.chains[support]
    most = max(len(p[0]) for p in plans)
    rows = np.full((2, most), -1, dtype=np.int64)
    size = np.zeros(2, dtype=np.int64)
    s0 = np.zeros((2, UNKNOWNS, UNKNOWNS))
    sz = np.zeros((2, most + 1, UNKNOWNS, UNKNOWNS))
    rx = np.zeros((2, most + 1, UNKNOWNS))
    axis_rows = np.full((2, UNKNOWNS - 1), -1, dtype=np.int64)
    for c, (names, c_s0, c_sz, c_rx, axes) in enumerate(plans):
        k, m = len(names), len(c_s0)
        rows[c, :k], size[c] = names, m
        s0[c, :m, :m] = c_s0
        sz[c, :k, :m, :m], sz[c, most, :m, :m] = c_sz[:k], c_sz[k]      # the CoM's coefficients last
        rx[c, :k, :m], rx[c, most, :m] = c_rx[:k], c_rx[k]
        axis_rows[c, :len(axes)] = axes
    return rows, size, s0, sz, rx, axis_rows


def kernel_plan(spec: Spec, support: Support | Side, hand_point: str, target: np.ndarray,
                extents: tuple[float, float, float, float], full: bool, consts: dict[str, float]) -> KernelPlan:
    """The kernel's constants for one problem (support foot, reaching hand, target [m], support rectangle [m],
    the cost's weights by :data:`CONST_NAMES`)."""
    mp = matrix_plan(spec, support)
    n_slots = len(mp.slots)
    parent = np.zeros(n_slots, dtype=np.int64)
    for start, stop, p_start, p_stop in mp.levels:
        for s in range(start, stop):
            parent[s] = p_start if p_stop - p_start == 1 else p_start + (s - start)
    slot_joint = np.full(n_slots, -1, dtype=np.int64)
    slot_fixed = np.full(n_slots, -1, dtype=np.int64)
    slot_joint[mp.joint_slots + 1] = np.arange(len(mp.var))
    slot_fixed[mp.fixed_slots + 1] = np.arange(len(mp.fixed_slots))

    _, origin_rows, origin_frames, offset_rows, offset_frames, offsets = point_layout(spec, support)
    row_slot = np.full(len(ALL_ROWS), -1, dtype=np.int64)
    row_point = np.zeros((len(ALL_ROWS), 3))
    row_slot[origin_rows] = origin_frames
    row_slot[offset_rows], row_point[offset_rows] = offset_frames, offsets
    const_rows = np.zeros((len(ALL_ROWS), 3))
    for i, (dx, dy) in enumerate(spec.foot.corners(as_side(support, "support"))):
        const_rows[ROW[f"{support}_foot_{i}"]] = (dx, dy, 0.0)
    pelvis = np.array([ROW["pelvis"], mp.slots["5"], mp.slots["6"]], dtype=np.int64)
    row_slot[ROW["pelvis"]] = -2                                               # the hips' midpoint
    weights = mass_weights(spec)

    com = full_com_plan(spec, support)
    rows, size, s0, sz, rx, axis_rows = _chains(Compliance(spec), support)
    sag = SwingLegSag(spec, support)
    shapes = shape_set(spec, support)
    g = spec.geometry
    ab = np.array([g.hip_x, -g.torso]) / np.hypot(g.hip_x, g.torso)
    return KernelPlan(
        parent, slot_joint, slot_fixed, mp.var.astype(np.int64), mp.sign[:, 0].astype(float),
        mp.offset[:, 0].astype(float), np.ascontiguousarray(mp.basis), np.ascontiguousarray(mp.fixed_local),
        np.ascontiguousarray(mp.root), row_slot, row_point, const_rows, pelvis, weights / weights.sum(),
        com.slots.astype(np.int64), com.masses.astype(float), np.ascontiguousarray(com.weighted), float(com.total),
        rows, size, s0, sz, rx, axis_rows,
        sag.slots.astype(np.int64), np.ascontiguousarray(sag.local), np.ascontiguousarray(sag.axes),
        sag.kp.astype(float),
        sag.link_slots.astype(np.int64), np.ascontiguousarray(sag.link_com), sag.link_mass.astype(float),
        shapes.slots.astype(np.int64), np.ascontiguousarray(shapes.local), shapes.is_box.astype(np.bool_),
        np.nan_to_num(shapes.half), np.ascontiguousarray(shapes.segment[:, 1, 2]), shapes.radius.astype(float),
        shapes.bound.astype(float), shapes.pairs.astype(np.int64),
        row_of(hand_point), row_of(f"{support[0]}_ankle"), ROW[f"{other_side(support)}_foot_0"],
        np.array([row_of(n) for n in ("neck", "pelvis", "l_sho_pitch", "r_sho_pitch")], dtype=np.int64), ab,
        np.asarray(target, dtype=float).reshape(3), np.asarray(extents, dtype=float), bool(full),
        np.array([float(consts[name]) for name in CONST_NAMES]), BOX_CORNERS, BOX_EDGES.astype(np.int64),
        SEGMENT_GRID, ROUNDS)
