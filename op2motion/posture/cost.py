"""The posture cost (book eq. 2.87, code 2.8-2.11), evaluated for a whole swarm at once.

    cost = PenaltySwingFootHeight + PenaltyStability(br) + |hand - target|            (the book)
         + W_VIOLATION * (how far a violated constraint is violated)                (beyond the book)
         + W_MARGIN * (MARGIN_CAP - min(margin, MARGIN_CAP))
         + W_UPRIGHT * torso_tilt^2 + PenaltySelfCollision

The book's terms are a step penalty of 100 when the swing foot's lowest corner is below the floor or the CoM
leaves the br-shrunk support rectangle, plus the hand's distance to the target [m]. The extra terms are small
tie-breakers (a centimetre of margin or 30° of torso tilt weigh about as much as 0.2-0.5 mm of reach), so that
among poses that reach the target the more stable, more upright one wins; and a screening penalty for obvious
self-collisions (a hand or elbow inside the torso, the swing foot over the support foot, knees crossing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..balance import FLOOR_TOLERANCE_M, PENALTY, support_extents
from ..errors import InputError
from ..joints import BookAngles
from ..kinematics import BodyPoints, forward
from ..kinematics.points import ROW, row_of
from ..spec import Spec

W_VIOLATION = 10.0     # cost per metre by which a violated constraint is violated, on top of the book's 100
W_MARGIN = 0.02        # cost per metre of stability margin below MARGIN_CAP
MARGIN_CAP_M = 0.02    # margins beyond this earn nothing more
W_UPRIGHT = 0.002      # cost per rad² of torso tilt from vertical
TORSO_HALF_M = (0.045, 0.055, 0.06)  # half extents (x, y, z) of the torso keep-out box for hands and elbows
KNEE_GAP_M = 0.045     # knees closer than this cross each other
FEET_GAP_M = 0.02      # swing foot this close above the support foot's area is a clash


@dataclass(frozen=True)
class PostureProblem:
    """What to reach: ``hand`` (left/right) to ``target`` [m] in the support-foot frame, standing on ``support``,
    CoM inside the support rectangle shrunk by ``br``, evaluated on kinematic ``model`` (dh or pb)."""

    support: str
    hand: str
    target: tuple[float, float, float]
    br: float = 0.7
    model: str = "dh"

    def validated(self) -> "PostureProblem":
        """Check the fields; raise :class:`InputError` on bad values."""
        if self.support not in ("left", "right"):
            raise InputError(f"support: expected 'left' or 'right', got {self.support!r}")
        if self.hand not in ("left", "right"):
            raise InputError(f"hand: expected 'left' or 'right', got {self.hand!r}")
        if len(self.target) != 3 or not all(np.isfinite(self.target)):
            raise InputError(f"target: expected 3 finite numbers [m], got {list(self.target)}")
        if not (np.isfinite(self.br) and 0.0 < self.br <= 1.0):
            raise InputError(f"br: expected a boundary ratio in (0, 1], got {self.br!r}")
        if self.model not in ("dh", "pb"):
            raise InputError(f"model: expected 'dh' or 'pb', got {self.model!r}")
        return self

    @property
    def hand_point(self) -> str:
        """Body-point name of the reaching hand."""
        return f"{self.hand}_hand"

    @property
    def name(self) -> str:
        """Default pose name, e.g. ``reach-ll-100-50-70-br70`` (hand, support, target in mm, br in %)."""
        mm = lambda v: f"{'m' if v < 0 else ''}{abs(round(v * 1000))}"  # noqa: E731
        x, y, z = self.target
        return f"reach-{self.hand[0]}{self.support[0]}-{mm(x)}-{mm(y)}-{mm(z)}-br{round(self.br * 100)}"


@dataclass(frozen=True)
class CostTerms:
    """Per-pose cost and its parts, each (N,)."""

    total: np.ndarray
    book: np.ndarray
    hand_error: np.ndarray
    margin: np.ndarray
    swing_min_z: np.ndarray
    tilt: np.ndarray
    collision: np.ndarray


_ARM_ROWS = [row_of(n) for n in ("left_hand", "right_hand", "l_el", "r_el")]
_ROWS = {n: row_of(n) for n in ("neck", "pelvis", "l_sho_pitch", "r_sho_pitch", "l_knee", "r_knee")}


def _torso_axes(data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Torso frame per pose from a (rows, 3, N) slab: axes (3 [x, y, z], 3, N) and the unnormalised up vector."""
    up = data[_ROWS["neck"]] - data[_ROWS["pelvis"]]
    z = up / np.sqrt(np.einsum("in,in->n", up, up))
    y = data[_ROWS["l_sho_pitch"]] - data[_ROWS["r_sho_pitch"]]
    y = y - np.einsum("in,in->n", y, z) * z
    y /= np.sqrt(np.einsum("in,in->n", y, y))
    x = np.stack([y[1] * z[2] - y[2] * z[1], y[2] * z[0] - y[0] * z[2], y[0] * z[1] - y[1] * z[0]])
    return np.stack([x, y, z]), up


def torso_tilt(points: BodyPoints) -> np.ndarray:
    """Angle [rad] between the pelvis->neck line and the vertical, (N,)."""
    up = points.data[_ROWS["neck"]] - points.data[_ROWS["pelvis"]]
    return np.arccos(np.clip(up[2] / np.sqrt(np.einsum("in,in->n", up, up)), -1.0, 1.0))


def self_collision_penalty(points: BodyPoints) -> np.ndarray:
    """Screening for obvious self-collisions: 100 per pose with a hand or elbow inside the torso, the swing foot
    over the support foot, or the knees crossing; (N,)."""
    data = points.data
    axes, _ = _torso_axes(data)
    centre = 0.5 * (data[_ROWS["neck"]] + data[_ROWS["pelvis"]])
    local = np.einsum("pjn,kjn->pkn", data[_ARM_ROWS] - centre, axes)          # (4 points, 3, N)
    bad = np.any(np.all(np.abs(local) < np.asarray(TORSO_HALF_M)[None, :, None], axis=1), axis=0)
    knees = data[_ROWS["l_knee"]] - data[_ROWS["r_knee"]]
    bad |= np.einsum("in,in->n", knees, knees) < KNEE_GAP_M ** 2
    swing = points.swing_foot_corners
    support = points.foot_corners(points.support)
    lo, hi = support[:, :, :2].min(axis=1), support[:, :, :2].max(axis=1)
    inside = np.all((swing[:, :, :2] > lo[:, None, :]) & (swing[:, :, :2] < hi[:, None, :]), axis=2)
    bad |= np.any(inside & (swing[:, :, 2] < FEET_GAP_M), axis=1)
    return np.where(bad, PENALTY, 0.0)


class CostModel:
    """The cost of one problem, prepared once (extents, target, rows) so that evaluating a swarm is lean."""

    def __init__(self, problem: PostureProblem, spec: Spec):
        self.problem, self.spec = problem.validated(), spec
        self.extents = np.array(support_extents(spec, problem.support, problem.br))  # front, back, left, right
        self.target = np.asarray(problem.target, dtype=float)[:, None]
        self.hand_row = row_of(problem.hand_point)
        self.swing_rows = slice(ROW[f"{'right' if problem.support == 'left' else 'left'}_foot_0"],
                                ROW[f"{'right' if problem.support == 'left' else 'left'}_foot_0"] + 4)

    def __call__(self, angles: BookAngles) -> CostTerms:
        """All cost terms for a batch of poses (book variables, support = the problem's)."""
        points = forward(angles, self.spec, self.problem.model)
        data = points.data
        hand = data[self.hand_row] - self.target
        hand_error = np.sqrt(np.einsum("in,in->n", hand, hand))
        swing_min_z = data[self.swing_rows, 2].min(axis=0)
        front, back, left, right = self.extents
        dx, dy = points.com[0], points.com[1]
        inside = np.minimum(np.minimum(front - dx, dx + back), np.minimum(left - dy, dy + right))
        outside = np.hypot(np.maximum(np.maximum(dx - front, -back - dx), 0.0),
                           np.maximum(np.maximum(dy - left, -right - dy), 0.0))
        margin = np.where(inside >= 0.0, inside, -outside)  # balance.stability_margin, support frame (sp 0, gamma 0)
        # The book's penalties (code 2.8, 2.9): PenaltyStability is 100 exactly where the margin is negative.
        below = swing_min_z < -FLOOR_TOLERANCE_M
        book = np.where(below, PENALTY, 0.0) + np.where(margin < 0.0, PENALTY, 0.0) + hand_error
        # Beyond the book: a slope inside the penalised region leads a swarm that starts there out of it.
        slope = W_VIOLATION * (np.where(below, -swing_min_z, 0.0) + np.maximum(-margin, 0.0))
        tilt = torso_tilt(points)
        collision = self_collision_penalty(points)
        total = (book + slope + W_MARGIN * (MARGIN_CAP_M - np.minimum(margin, MARGIN_CAP_M))
                 + W_UPRIGHT * tilt * tilt + collision)
        return CostTerms(total, book, hand_error, margin, swing_min_z, tilt, collision)


def evaluate_cost(angles: BookAngles, problem: PostureProblem, spec: Spec) -> CostTerms:
    """All cost terms for a batch of poses (book variables, support = problem.support)."""
    return CostModel(problem, spec)(angles)
