"""Where each link of the robot rides on the book's D-H chain, found once per spec and support foot.

The D-H chain has its own frames (the book's), not the description's link frames. For every link of the spec, a
few random poses are walked through the official joint table (:mod:`.tree`) and through the chain
(:func:`.dh_chain.matrix_frames`); the link is attached to the chain frame in which its own frame does not move, at
a constant transform. With these attachments the D-H evaluator places the link inertials (the full-inertia CoM,
:class:`FullComPlan`) and the collision shapes (:mod:`.shapes`) for a whole batch of poses at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.errors import SpecError
from op2motion.kinematics.dh_chain import cached, matrix_frames, matrix_plan
from op2motion.kinematics.tree import link_frames
from op2motion.robot.joints import BookAngles, book_to_servo
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support

CALIBRATION_POSES = 3
ATTACHED_M = 1e-9   # a link rides on a chain frame when its frame keeps its place in that frame to this [m or rad]


@dataclass(frozen=True)
class Attachment:
    """A link fixed to the chain: the chain frame's slot (see :class:`.dh_chain.MatrixPlan`) and the link frame
    in that chain frame (4, 4) [m]."""

    slot: int
    local: np.ndarray


def attachments(spec: Spec, support: Support | Side) -> dict[str, Attachment]:
    """``{link: Attachment}`` for every link of ``spec`` with ``support`` as the chain's root (cached)."""
    return cached("links", spec, support, _calibrate)


def _calibrate(spec: Spec, support: Support | Side) -> dict[str, Attachment]:
    rng = np.random.default_rng(0)
    angles = BookAngles.random(CALIBRATION_POSES, rng, support)
    frames = matrix_frames(angles.vector(), spec, support)                  # (slots, k, 4, 4) in the sole frame
    servo = book_to_servo(angles, spec)
    sole_drop = np.array([0.0, 0.0, -spec.foot.sole_below_ankle])
    in_sole: dict[str, list[np.ndarray]] = {}
    for k in range(CALIBRATION_POSES):
        tree = link_frames(spec, servo[k])
        r_foot, p_foot = tree[spec.joint(f"{support[0]}_ank_roll").child]
        p_sole = p_foot + r_foot @ sole_drop
        for link, (r, p) in tree.items():
            t = np.eye(4)
            t[:3, :3], t[:3, 3] = r_foot.T @ r, r_foot.T @ (p - p_sole)
            in_sole.setdefault(link, []).append(t)
    inverse = np.linalg.inv(frames)                                         # (slots, k, 4, 4)
    found = {}
    for link, poses in in_sole.items():
        local = inverse @ np.asarray(poses)[None]                           # (slots, k, 4, 4)
        spread = np.ptp(local[..., :3, :], axis=1).reshape(len(frames), -1).max(axis=1)
        slot = int(np.argmin(spread))
        if spread[slot] >= ATTACHED_M:
            raise SpecError(f"link {link!r} moves with no frame of the D-H chain", spec.path)
        found[link] = Attachment(slot, local[slot, 0])
    return found


@dataclass(frozen=True)
class FullComPlan:
    """Where the spec's link inertials sit in the chain: for each chain frame that carries mass, the mass [kg] and
    the mass-weighted centre of mass in that frame [kg·m]; the total mass [kg]."""

    frames: tuple[str, ...]
    slots: np.ndarray
    masses: np.ndarray
    weighted: np.ndarray
    total: float


def full_com_plan(spec: Spec, support: Support | Side) -> FullComPlan:
    """The plan of the full-inertia CoM for ``support`` (computed once per spec)."""
    return cached("fullcom", spec, support, _build_full_com_plan)


def _build_full_com_plan(spec: Spec, support: Support | Side) -> FullComPlan:
    attached = attachments(spec, support)
    masses: dict[int, float] = {}
    weighted: dict[int, np.ndarray] = {}
    for inertial in spec.inertials:
        at = attached[inertial.link]
        com = at.local[:3, :3] @ np.asarray(inertial.link_com) + at.local[:3, 3]
        masses[at.slot] = masses.get(at.slot, 0.0) + inertial.mass
        weighted[at.slot] = weighted.get(at.slot, np.zeros(3)) + inertial.mass * com
    slot_of = {slot: name for name, slot in matrix_plan(spec, support).slots.items()}
    slots = sorted(masses)
    return FullComPlan(tuple(slot_of[s] for s in slots), np.array(slots), np.array([masses[s] for s in slots]),
                       np.array([weighted[s] for s in slots]), float(sum(masses.values())))
