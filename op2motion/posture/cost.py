"""The posture cost (book eq. 2.87, code 2.8-2.11), evaluated for a whole swarm at once.

    cost = PenaltySwingFootHeight + PenaltyStability(br) + |hand - target|            (the book)
         + W_VIOLATION * (how far a violated constraint is violated)                (beyond the book)
         + W_MARGIN * (MARGIN_CAP - min(margin, MARGIN_CAP))
         + W_UPRIGHT * torso_tilt^2 + PenaltySelfCollision

The book's terms are a step penalty of 100 when the swing foot's lowest corner is below the floor or the CoM
leaves the br-shrunk support rectangle, plus the hand's distance to the target [m]. The extra terms are small
tie-breakers (a centimetre of margin or 30° of torso tilt weigh about as much as 0.2-0.5 mm of reach), so that
among poses that reach the target the more stable, more upright one wins; and a screening penalty for obvious
self-collisions (:class:`Screen`: a hand or elbow inside the torso, the swing foot over the support foot, knees
crossing), sized from the spec's collision shapes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import book
from ..balance import (
    COM_MODEL_FULL,
    COM_MODELS,
    FLOOR_TOLERANCE_M,
    PENALTY,
    check_br,
    rectangle_margin,
    support_extents,
)
from ..errors import InputError
from ..joints import BookAngles, check_support
from ..kinematics import MODELS, BodyPoints, forward
from ..kinematics.points import ROW, row_of
from ..spec import Spec, swing_of
from .compliance import Compliance

W_VIOLATION = 10.0     # cost per metre by which a violated constraint is violated, on top of the book's 100
W_MARGIN = 0.02        # cost per metre of stability margin below MARGIN_CAP
MARGIN_CAP_M = 0.02    # margins beyond this earn nothing more
W_UPRIGHT = 0.002      # cost per rad² of torso tilt from vertical
SAG_TILT_LIMIT_RAD = 0.105   # 6°: the torso may turn this much as the servos take the load (physics calls 10° a fall)
TARGET_LIMIT_M = 1.0   # a target farther than this from the support foot is not a target for a 45 cm robot


@dataclass(frozen=True)
class PostureProblem:
    """What to reach: ``hand`` (left/right) to ``target`` [m] in the support-foot frame, standing on ``support``,
    CoM inside the support rectangle shrunk by ``br``, evaluated on kinematic ``model`` (dh or pb)."""

    support: str
    hand: str
    target: tuple[float, float, float]
    br: float = book.DEFAULT_PROBLEM.br
    model: str = "dh"
    com_model: str = COM_MODEL_FULL

    @classmethod
    def from_scenario(cls, scenario: book.Scenario, model: str = "dh",
                      com_model: str = COM_MODEL_FULL) -> "PostureProblem":
        """The problem of one of the book's scenarios (or the default problem)."""
        return cls(scenario.support, scenario.hand, scenario.target, scenario.br, model, com_model)

    def validated(self) -> "PostureProblem":
        """Check the fields; raise :class:`InputError` on bad values."""
        check_support(self.support)
        if self.hand not in ("left", "right"):
            raise InputError(f"expected 'left' or 'right', got {self.hand!r}", "hand")
        if len(self.target) != 3 or not all(np.isfinite(self.target)):
            raise InputError(f"expected 3 finite numbers [m], got {list(self.target)}", "target")
        if max(abs(v) for v in self.target) > TARGET_LIMIT_M:
            raise InputError(f"expected coordinates within ±{TARGET_LIMIT_M:g} m, got {list(self.target)}", "target")
        check_br(self.br)
        if self.model not in MODELS:
            raise InputError(f"expected 'dh' or 'pb', got {self.model!r}", "model")
        if self.com_model not in COM_MODELS:
            raise InputError(f"expected one of {', '.join(COM_MODELS)}, got {self.com_model!r}", "com_model")
        if self.com_model == COM_MODEL_FULL and self.model != "dh":
            raise InputError("the full-inertia CoM needs the D-H model; choose --model dh or --com-model book",
                             "com_model")
        return self

    def extents(self, spec: Spec) -> tuple[float, float, float, float]:
        """The support rectangle (front, back, left, right) [m] of :attr:`com_model`, shrunk by ``br``."""
        return support_extents(spec, self.support, self.br, self.com_model)

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
    """Per-pose cost and its parts, each (N,): total and book cost, hand error [m], stability margin [m] (of the
    settled CoM for the full-inertia model), lowest swing-foot corner [m], torso tilt [rad], self-collision
    penalty, and the torso turn as the servos take the load [rad] (0 for the book's rigid model)."""

    total: np.ndarray
    book: np.ndarray
    hand_error: np.ndarray
    margin: np.ndarray
    swing_min_z: np.ndarray
    tilt: np.ndarray
    collision: np.ndarray
    sag_tilt: np.ndarray


@dataclass(frozen=True)
class Screen:
    """Sizes of the self-collision screen [m], from the spec's collision shapes: the torso box (centre and half
    extents in the torso frame) grown by the forearm radius, the shin width (knees closer than this cross) and
    the foot box thickness (a swing sole lower than this over the support foot clashes with it)."""

    torso_centre: np.ndarray
    torso_half: np.ndarray
    knee_gap: float
    foot_thickness: float

    @classmethod
    def of(cls, spec: Spec) -> "Screen":
        """The screen of ``spec`` (its first box on the torso, knee and foot links, cylinder on the forearm)."""
        def shape(joint: str | None, kind: str):  # the collision shape of a joint's child link (or the root)
            link = spec.root_link if joint is None else spec.joint(joint).child
            found = spec.collisions_of(link, kind)
            if not found:
                raise InputError(f"the spec has no {kind} collision shape on {link}, which the screen needs", "spec")
            return found[0]

        torso, forearm = shape(None, "box"), shape("l_el", "cylinder")
        return cls(np.asarray(torso.origin_xyz), np.asarray(torso.size) / 2 + forearm.size[0],
                   shape("l_knee", "box").size[1], shape("l_ank_roll", "box").size[2])


_ARM_ROWS = [row_of(n) for n in ("left_hand", "right_hand", "l_el", "r_el")]
_ROWS = {n: row_of(n) for n in ("neck", "pelvis", "l_sho_pitch", "r_sho_pitch", "l_knee", "r_knee")}


def torso_axes(data: np.ndarray, spec: Spec) -> np.ndarray:
    """The torso (``body_link``) frame's axes per pose, (3 [x, y, z], 3, N), from a (rows, 3, N) slab: y from the
    shoulder-pitch axes, x and z from the pelvis point, which lies at (hip_x, 0, -torso) in that frame."""
    y = data[_ROWS["l_sho_pitch"]] - data[_ROWS["r_sho_pitch"]]
    y = y / np.sqrt(np.einsum("in,in->n", y, y))
    u = data[_ROWS["pelvis"]] - data[_ROWS["neck"]]
    u = u / np.sqrt(np.einsum("in,in->n", u, u))
    g = spec.geometry
    a, b = np.array([g.hip_x, -g.torso]) / np.hypot(g.hip_x, g.torso)   # u = a x + b z
    w = np.stack([y[1] * u[2] - y[2] * u[1], y[2] * u[0] - y[0] * u[2],   # y × u = -a z + b x
                  y[0] * u[1] - y[1] * u[0]])
    return np.stack([b * w + a * u, y, b * u - a * w])


def torso_tilt(points: BodyPoints, spec: Spec, axes: np.ndarray | None = None) -> np.ndarray:
    """Angle [rad] between the torso's z axis and the vertical, (N,) (``axes``: :func:`torso_axes`, if known)."""
    axes = torso_axes(points.data, spec) if axes is None else axes
    return np.arccos(np.clip(axes[2, 2], -1.0, 1.0))


def self_collision_penalty(points: BodyPoints, spec: Spec, screen: Screen | None = None,
                           axes: np.ndarray | None = None) -> np.ndarray:
    """Screening for obvious self-collisions: 100 per pose with a hand or elbow inside the torso, the swing foot
    over the support foot, or the knees crossing; (N,)."""
    screen = screen or Screen.of(spec)
    data = points.data
    axes = torso_axes(data, spec) if axes is None else axes
    local = np.einsum("pjn,kjn->pkn", data[_ARM_ROWS] - data[_ROWS["neck"]], axes) - screen.torso_centre[None, :, None]
    bad = np.any(np.all(np.abs(local) < screen.torso_half[None, :, None], axis=1), axis=0)
    knees = data[_ROWS["l_knee"]] - data[_ROWS["r_knee"]]
    bad |= np.einsum("in,in->n", knees, knees) < screen.knee_gap ** 2
    swing = points.swing_foot_corners
    support = points.foot_corners(points.support)
    lo, hi = support[:, :, :2].min(axis=1), support[:, :, :2].max(axis=1)
    inside = np.all((swing[:, :, :2] > lo[:, None, :]) & (swing[:, :, :2] < hi[:, None, :]), axis=2)
    bad |= np.any(inside & (swing[:, :, 2] < screen.foot_thickness), axis=1)
    return np.where(bad, PENALTY, 0.0)


class CostModel:
    """The cost of one problem, prepared once (extents, target, rows) so that evaluating a swarm is lean."""

    def __init__(self, problem: PostureProblem, spec: Spec):
        self.problem, self.spec = problem.validated(), spec
        self.extents = problem.extents(spec)
        self.full = problem.com_model == COM_MODEL_FULL
        self.compliance = Compliance(spec) if self.full else None
        self.target = np.asarray(problem.target, dtype=float)[:, None]
        self.hand_row = row_of(problem.hand_point)
        first = ROW[f"{swing_of(problem.support)}_foot_0"]
        self.swing_rows = slice(first, first + 4)
        self.screen = Screen.of(spec)

    def __call__(self, angles: BookAngles) -> CostTerms:
        """All cost terms for a batch of poses (book variables, support = the problem's)."""
        points = forward(angles, self.spec, self.problem.model, full_com=self.full)
        data = points.data
        hand = data[self.hand_row] - self.target
        hand_error = np.sqrt(np.einsum("in,in->n", hand, hand))
        swing_min_z = data[self.swing_rows, 2].min(axis=0)
        if self.compliance is not None:   # the body physics simulates: full inertia on compliant servos
            settled = self.compliance.settle(points, points.com_full)
            com_xy, sag_tilt = settled.com_xy, settled.tilt      # infinite where no equilibrium exists
        else:                             # the book's body: lumped masses on rigid joints
            com_xy, sag_tilt = points.com[:2], np.zeros(points.n)
        margin = rectangle_margin(com_xy[0], com_xy[1], self.extents)  # world = support frame
        sag_excess = np.maximum(np.minimum(sag_tilt, 1.0) - SAG_TILT_LIMIT_RAD, 0.0)
        # The book's penalties (code 2.8, 2.9): PenaltyStability is 100 exactly where the margin is negative; on
        # compliant servos also where the load would turn the torso over the limit.
        below = swing_min_z < -FLOOR_TOLERANCE_M
        unstable = (margin < 0.0) | (sag_excess > 0.0)
        book_cost = np.where(below, PENALTY, 0.0) + np.where(unstable, PENALTY, 0.0) + hand_error
        # Beyond the book: a slope inside the penalised region leads a swarm that starts there out of it.
        slope = W_VIOLATION * (np.where(below, -swing_min_z, 0.0) + np.minimum(np.maximum(-margin, 0.0), 1.0)
                               + 0.1 * sag_excess)
        axes = torso_axes(data, self.spec)
        tilt = torso_tilt(points, self.spec, axes)
        collision = self_collision_penalty(points, self.spec, self.screen, axes)
        total = (book_cost + slope + W_MARGIN * (MARGIN_CAP_M - np.minimum(margin, MARGIN_CAP_M))
                 + W_UPRIGHT * tilt * tilt + collision)
        return CostTerms(total, book_cost, hand_error, margin, swing_min_z, tilt, collision, sag_tilt)


def evaluate_cost(angles: BookAngles, problem: PostureProblem, spec: Spec) -> CostTerms:
    """All cost terms for a batch of poses (book variables, support = problem.support)."""
    return CostModel(problem, spec)(angles)
