"""The book's Denavit-Hartenberg chain as one table, with the real robot's lengths (see :mod:`.dh`).

The chain and frame numbering follow the book (seed 001, code 2.5 ``GenMotionsWithDH``, tables 2.3-2.5): frame 0
on the support ankle, B1-B6 up the support leg to the swing hip, B7-B12 down the swing leg to its sole, frames 13-16
(left arm), 17-20 (right arm) and 21-23 (neck, head) hung from frame 6 by the book's additional transforms. Both
support feet and the transverse angles psi are supported. The chain adds the fixed transforms the book leaves out:
the hip-yaw axes 5 mm behind the torso origin and the 0.016 m forward elbow offset; the shoulder-roll offset is
0.0245 m (book 0.024). :class:`MatrixPlan` lays the table out for the 4x4 matrix evaluator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, TypeVar

import numpy as np

from op2motion.kinematics.points import ROW
from op2motion.robot.spec import BOOK_VARS, Spec
from op2motion.robot.support import Side, Support, other_side

_HALF_PI = math.pi / 2
# World axes of frame 0 (book W with gamma = 0): x0 = +Y, y0 = +Z, z0 = +X.
W0 = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
# Book eq. 2.58: the additional transform that turns the hip-roll DH frame into the hip-yaw frame.
_HIP = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
# Book T13_6/T17_6 (shoulders) and T21_6 (neck) rotations, for left and right support.
_ARM_ROT = {True: ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
            False: ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0))}
_NECK_ROT = {True: ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
             False: ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))}
_V = {name: i for i, name in enumerate(BOOK_VARS)}


@dataclass(frozen=True)
class ChainStep:
    """One frame of the chain: ``frame = parent · DH(sign·q[var] + offset, d, a, alpha) · Trans(trans) · Rot(rot)``;
    a step without ``var`` is the fixed part alone (the book's additional transforms)."""

    frame: str
    parent: str
    var: int | None = None
    sign: float = 1.0
    offset: float = 0.0
    d: float = 0.0
    a: float = 0.0
    alpha: float = 0.0
    trans: tuple[float, float, float] | None = None
    rot: tuple[tuple[float, ...], ...] | None = None


_CACHE: dict[tuple[str, str, str], Any] = {}
T = TypeVar("T")


def cached(kind: str, spec: Spec, support: Support | Side, build: Callable[[Spec, Support | Side], T]) -> T:
    """``build(spec, support)``, made once per (kind, spec content, support)."""
    key = (kind, spec.sha256, support)
    if key not in _CACHE:
        _CACHE[key] = build(spec, support)
    built: T = _CACHE[key]
    return built


def chain(spec: Spec, support: Support | Side) -> tuple[ChainStep, ...]:
    """The book's D-H chain with the real robot's lengths, rooted at the ``support`` ankle (frame "0")."""
    return cached("chain", spec, support, _build_chain)


def _build_chain(spec: Spec, support: Support | Side) -> tuple[ChainStep, ...]:
    g = spec.geometry
    left = support == "left"
    sgn = 1.0 if left else -1.0
    hw, sh, fwd, pi = g.hip_half_width, g.shoulder_half_width, -g.hip_x * sgn, math.pi
    steps = [
        ChainStep("1", "0", _V["phi1"], 1, _HALF_PI, alpha=_HALF_PI),
        ChainStep("2", "1", _V["th1"], -1, _HALF_PI, a=g.calf),
        ChainStep("3", "2", _V["th2"], -1, a=g.thigh),
        ChainStep("4", "3", _V["th3"], -1, alpha=-_HALF_PI),
        ChainStep("5", "4", _V["phi2"], 1, a=g.hip_yaw_to_roll, rot=_HIP),
        ChainStep("6", "5", _V["psi1"], 1, 0.0 if left else pi, a=2.0 * hw),
        ChainStep("7", "6", _V["psi2"], 1, alpha=-sgn * _HALF_PI, trans=(0.0, sgn * g.hip_yaw_to_roll, 0.0)),
        ChainStep("8", "7", _V["phi3"], 1, -sgn * _HALF_PI, alpha=-_HALF_PI),
        ChainStep("9", "8", _V["th4"], -1, pi, a=g.thigh),
        ChainStep("10", "9", _V["th5"], -1, a=g.calf),
        ChainStep("11", "10", _V["th6"], -1, alpha=_HALF_PI),
        ChainStep("12", "11", _V["phi4"], 1, a=g.ankle_to_sole),
        # Upper body hung from frame 6; the torso origin sits -hip_x forward of the hip-yaw axes.
        ChainStep("13", "6", trans=(-hw - sgn * sh, fwd, g.torso), rot=_ARM_ROT[left]),
        ChainStep("17", "6", trans=(-hw + sgn * sh, fwd, g.torso), rot=_ARM_ROT[left]),
        ChainStep("21", "6", trans=(-hw, fwd, g.torso), rot=_NECK_ROT[left]),
        ChainStep("22", "21", _V["psi3"], 1, d=g.head_tilt_height, alpha=_HALF_PI),
        ChainStep("23", "22", _V["th11"], -1, _HALF_PI, a=g.head_length),
    ]
    for first, pitch, roll, elbow, lateral in ((13, "th7", "phi5", "th8", 1.0), (17, "th9", "phi6", "th10", -1.0)):
        f = str(first)
        steps += [
            ChainStep(str(first + 1), f, _V[pitch], -1, d=lateral * g.shoulder_roll_lateral, a=g.shoulder_roll_drop,
                 alpha=_HALF_PI),
            ChainStep(str(first + 2), str(first + 1), _V[roll], 1, -pi, a=g.upper_arm, alpha=-_HALF_PI,
                 trans=(0.0, -g.elbow_forward, 0.0)),  # the real elbow offset, then the elbow axis
            ChainStep(str(first + 3), str(first + 2), _V[elbow], -1, a=g.lower_arm),
        ]
    return tuple(steps)


def chain_points(spec: Spec, support: Support | Side) -> tuple[tuple[str, str, tuple[float, float, float]], ...]:
    """(row, frame, point in that frame) of every body point the chain gives (pelvis and soles aside)."""
    g = spec.geometry
    s, w = ("l", "r") if support == "left" else ("r", "l")
    o = (0.0, 0.0, 0.0)
    rows = [(f"{s}_ankle", "0", o), (f"{s}_knee", "2", o), (f"{s}_hip", "3", o), (f"{s}_hip_yaw", "5", o),
            (f"{w}_hip_yaw", "6", o), (f"{w}_hip", "7", o), (f"{w}_knee", "9", o), (f"{w}_ankle", "10", o),
            (f"{other_side(support)}_sole", "12", o),
            ("neck", "21", o), ("head_pan", "21", (0.0, 0.0, g.head_pan_height)), ("head_tilt", "22", o),
            ("head_top", "23", o), ("l_sho_pitch", "13", o), ("l_sho_roll", "14", o), ("l_el", "15", o),
            ("left_hand", "16", o), ("r_sho_pitch", "17", o), ("r_sho_roll", "18", o), ("r_el", "19", o),
            ("right_hand", "20", o)]
    rows += [(f"{other_side(support)}_foot_{i}", "12", (0.0, dy, dx))        # frame 12: y left, z forward
             for i, (dx, dy) in enumerate(spec.foot.corners(other_side(support)))]
    return tuple(rows)


@dataclass(frozen=True)
class MatrixPlan:
    """Constants of the matrix evaluator for one spec and support foot. Frames are stored in level order (slot 0 is
    frame "0"), so that each level of the tree, and the parents of each level, are contiguous slices."""

    var: np.ndarray          # (J,) book-variable index of each joint step, in slot order
    sign: np.ndarray         # (J, 1)
    offset: np.ndarray       # (J, 1)
    basis: np.ndarray        # (J, 3, 16): local matrix = [cos(delta), sin(delta), 1] @ basis
    joint_slots: np.ndarray  # (J,) slot index - 1 of each joint step in the local array
    fixed_slots: np.ndarray  # slot index - 1 of the fixed-only steps
    fixed_local: np.ndarray  # (F, 4, 4) their constant transforms
    root: np.ndarray         # (4, 4) frame 0
    levels: tuple[tuple[int, int, int, int], ...]  # ((start, stop, parent start, parent stop), ...) per level
    slots: dict[str, int]    # frame name -> slot


def matrix_plan(spec: Spec, support: Support | Side) -> MatrixPlan:
    return cached("matrix", spec, support, _build_matrix_plan)


def _build_matrix_plan(spec: Spec, support: Support | Side) -> MatrixPlan:
    steps = chain(spec, support)
    by_frame = {st.frame: st for st in steps}
    # Level order: each level lists children of the previous level's frames in that order, so ranges are contiguous.
    order: list[str] = []
    previous, levels = ["0"], []
    while len(order) < len(steps):
        level = [st.frame for parent in previous for st in steps if st.parent == parent]
        parents = sorted({by_frame[f].parent for f in level}, key=previous.index)
        start = len(order) + 1
        order += level
        first = (start - len(previous)) if previous != ["0"] else 0
        p_start = first + previous.index(parents[0])
        levels.append((start, start + len(level), p_start, p_start + len(parents)))
        i = previous.index(parents[0])
        if previous[i:i + len(parents)] != parents or len(parents) not in (1, len(level)):
            raise RuntimeError("chain levels must fan out from one frame or continue one-to-one")
        previous = level
    slots = {"0": 0, **{f: i + 1 for i, f in enumerate(order)}}
    joint = [f for f in order if by_frame[f].var is not None]
    fixed_only = [f for f in order if by_frame[f].var is None]

    def fixed_of(st: ChainStep) -> np.ndarray:
        m = np.eye(4)
        if st.rot is not None:
            m[:3, :3] = np.asarray(st.rot)
        if st.trans is not None:
            m[:3, 3] = st.trans
        return m

    basis = np.zeros((len(joint), 3, 4, 4))
    for j, f in enumerate(joint):
        st = by_frame[f]
        ca, sa = round(math.cos(st.alpha), 15), round(math.sin(st.alpha), 15)
        # DHMat (book eq. 2.40) = cos(delta) K_cos + sin(delta) K_sin + K_one, then the step's fixed part.
        k = basis[j]
        k[0, 0, 0], k[0, 0, 3], k[0, 1, 1], k[0, 1, 2] = 1.0, st.a, ca, -sa
        k[1, 0, 1], k[1, 0, 2], k[1, 1, 0], k[1, 1, 3] = -ca, sa, 1.0, st.a
        k[2, 2, 1], k[2, 2, 2], k[2, 2, 3], k[2, 3, 3] = sa, ca, st.d, 1.0
        basis[j] = k @ fixed_of(st)
    root = np.eye(4)
    root[:3, :3], root[2, 3] = np.asarray(W0), spec.geometry.ankle_to_sole
    return MatrixPlan(np.array([by_frame[f].var for f in joint]),
                       np.array([by_frame[f].sign for f in joint])[:, None],
                       np.array([by_frame[f].offset for f in joint])[:, None], basis.reshape(len(joint), 3, 16),
                       np.array([slots[f] - 1 for f in joint]), np.array([slots[f] - 1 for f in fixed_only]),
                       np.array([fixed_of(by_frame[f]) for f in fixed_only]), root, tuple(levels), slots)


def matrix_frames(q: np.ndarray, spec: Spec, support: Support | Side) -> np.ndarray:
    """Every frame of the chain for each pose, (slots, m, 4, 4), slot order of :func:`matrix_plan`."""
    m = q.shape[0]
    plan = matrix_plan(spec, support)
    delta = plan.sign * q.T[plan.var] + plan.offset                  # (joints, m)
    coef = np.empty((len(plan.var), m, 3))
    coef[:, :, 0], coef[:, :, 1], coef[:, :, 2] = np.cos(delta), np.sin(delta), 1.0
    local = np.empty((len(plan.slots) - 1, m, 4, 4))
    local[plan.joint_slots] = (coef @ plan.basis).reshape(len(plan.var), m, 4, 4)
    local[plan.fixed_slots] = plan.fixed_local[:, None]
    frames = np.empty((len(plan.slots), m, 4, 4))
    frames[0] = plan.root
    for start, stop, p_start, p_stop in plan.levels:   # one level of the tree in one batched product
        np.matmul(frames[p_start:p_stop], local[start - 1:stop - 1], out=frames[start:stop])
    return frames


#: The matrix evaluator's point gathering: (None, origin rows, their slots, offset rows, their slots, offsets).
PointLayout = tuple[None, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def point_layout(spec: Spec, support: Support | Side) -> PointLayout:
    """Index arrays for the matrix evaluator's point gathering (cached per spec and support)."""
    return cached("layout", spec, support, _build_point_layout)


def _build_point_layout(spec: Spec, support: Support | Side) -> PointLayout:
    slots = matrix_plan(spec, support).slots
    points = chain_points(spec, support)
    origin = [(ROW[r], slots[f]) for r, f, p in points if p == (0.0, 0.0, 0.0)]
    offset = [(ROW[r], slots[f], p) for r, f, p in points if p != (0.0, 0.0, 0.0)]
    return (None, np.array([r for r, _ in origin]), np.array([f for _, f in origin]),
            np.array([r for r, _, _ in offset]), np.array([f for _, f, _ in offset]),
            np.array([p for _, _, p in offset], dtype=float))
