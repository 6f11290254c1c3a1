"""The posture cost (book eq. 2.87, code 2.8-2.11), evaluated for a whole swarm at once.

    cost = PenaltySwingFootHeight + PenaltyStability(br) + |hand - target|            (the book)
         + W_VIOLATION * (how far a violated constraint is violated)                (beyond the book)
         + W_MARGIN * (MARGIN_CAP - min(margin, MARGIN_CAP))
         + W_UPRIGHT * torso_tilt^2
         + 100 * (self-clearance < SELF_CLEARANCE_M) + W_VIOLATION * (how far below it)

The book's terms are a step penalty of 100 when the swing foot's lowest corner is below the floor or the CoM
leaves the br-shrunk support rectangle, plus the hand's distance to the target [m]. The extra terms are small
tie-breakers (a centimetre of margin or 30° of torso tilt weigh about as much as 0.2-0.5 mm of reach), so that
among poses that reach the target the more stable, more upright one wins; and a screening penalty for obvious
self-collisions: the least distance between the spec's collision shapes (the ones physics simulates) on the D-H
chain (:mod:`..kinematics.shapes`) must be at least :data:`SELF_CLEARANCE_M`, whichever model the hand and CoM
come from.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from op2motion import book
from op2motion.errors import InputError, ref
from op2motion.kinematics import MODELS, BodyPoints, ModelName, forward
from op2motion.kinematics.dh import MATRIX_BELOW, forward_dh_frames
from op2motion.kinematics.dh_chain import matrix_frames
from op2motion.kinematics.points import ROW, row_of
from op2motion.kinematics.shapes import clearances, shape_set
from op2motion.model.compliance import Compliance, SwingLegSag
from op2motion.robot.balance import (
    COM_MODEL_FULL,
    COM_MODELS,
    FLOOR_TOLERANCE_M,
    PENALTY,
    ComModel,
    check_br,
    rectangle_margin,
    support_extents,
)
from op2motion.robot.joints import BookAngles
from op2motion.robot.spec import GRAVITY_M_S2, Spec
from op2motion.robot.support import LIFTED_M, Side, Support, as_side, other_side

if TYPE_CHECKING:
    from op2motion.posture.kernel_plan import KernelPlan

W_VIOLATION = 10.0     # cost per metre by which a violated constraint is violated, on top of the book's 100
W_MARGIN = 0.02        # cost per metre of stability margin below MARGIN_CAP
MARGIN_CAP_M = 0.02    # margins beyond this earn nothing more
W_UPRIGHT = 0.002      # cost per rad² of torso tilt from vertical
SAG_TILT_LIMIT_RAD = 0.105   # 6°: the torso may turn this much as the servos take the load (physics calls 10° a fall)
SELF_CLEARANCE_M = 0.004   # least distance between collision shapes: covers the shape approximations (<= 3 mm)
CLEARANCE_EXACT_M = 0.01   # clearances are computed exactly below this (above it, a lower bound is enough)
TARGET_LIMIT_M = 1.0   # a target farther than this from the support foot is not a target for a 45 cm robot


@dataclass(frozen=True)
class PostureProblem:
    """What to reach: ``hand`` (left/right) to ``target`` [m] in the support-foot frame, standing on ``support``,
    CoM inside the support rectangle shrunk by ``br``, evaluated on kinematic ``model`` (dh or pb)."""

    support: Side
    hand: Side
    target: tuple[float, float, float]
    br: float = book.DEFAULT_PROBLEM.br
    model: ModelName = "dh"
    com_model: ComModel = COM_MODEL_FULL

    @classmethod
    def from_scenario(cls, scenario: book.Scenario, model: ModelName = "dh",
                      com_model: ComModel = COM_MODEL_FULL) -> "PostureProblem":
        """The problem of one of the book's scenarios (or the default problem)."""
        return cls(as_side(scenario.support, "support"), as_side(scenario.hand, "hand"), scenario.target, scenario.br,
                   model, com_model)

    def validated(self) -> "PostureProblem":
        """Check the fields; raise :class:`InputError` on bad values."""
        as_side(self.support, "support")
        as_side(self.hand, "hand")
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
            raise InputError(f"the full-inertia CoM needs the D-H model; choose {ref('model')} dh or "
                             f"{ref('com_model')} book", "com_model")
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
        def mm(v: float) -> str:
            return f"{'m' if v < 0 else ''}{abs(round(v * 1000))}"

        x, y, z = self.target
        return f"reach-{self.hand[0]}{self.support[0]}-{mm(x)}-{mm(y)}-{mm(z)}-br{round(self.br * 100)}"


@dataclass(frozen=True)
class CostTerms:
    """Per-pose cost and its parts, each (N,): total and book cost, hand error [m], stability margin [m] (of the
    settled CoM for the full-inertia model), lowest swing-foot corner [m], torso tilt [rad], self-collision
    penalty, the torso turn as the servos take the load [rad] (0 for the book's rigid model) and the least
    clearance between collision shapes [m] (exact below :data:`CLEARANCE_EXACT_M`); ``swing_lift`` [m] is how far
    the swing foot clears its limit (feasible at >= 0): the book's floor for its rigid model, :data:`LIFTED_M`
    above the floor after the sag on compliant servos."""

    total: np.ndarray
    book: np.ndarray
    hand_error: np.ndarray
    margin: np.ndarray
    swing_min_z: np.ndarray
    tilt: np.ndarray
    collision: np.ndarray
    sag_tilt: np.ndarray
    clearance: np.ndarray
    swing_lift: np.ndarray


_ROWS = {n: row_of(n) for n in ("neck", "pelvis", "l_sho_pitch", "r_sho_pitch")}


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
    tilt: np.ndarray = np.arccos(np.clip(axes[2, 2], -1.0, 1.0))
    return tilt


def self_collision_penalty(frames: np.ndarray, spec: Spec, support: Support | Side) -> tuple[np.ndarray, np.ndarray]:
    """The self-collision penalty (N,) and the least clearance [m] (N,) of a batch of poses given by their D-H chain
    frames (slots, N, 4, 4): 100 plus the slope where the clearance is below :data:`SELF_CLEARANCE_M`."""
    clearance = clearances(frames, shape_set(spec, support), CLEARANCE_EXACT_M).min(axis=0)
    deficit = np.maximum(SELF_CLEARANCE_M - clearance, 0.0)
    return np.where(deficit > 0.0, PENALTY, 0.0) + W_VIOLATION * deficit, clearance


class CostModel:
    """The cost of one problem, prepared once (extents, target, rows) so that evaluating a swarm is lean."""

    def __init__(self, problem: PostureProblem, spec: Spec):
        self.problem, self.spec = problem.validated(), spec
        self.extents = problem.extents(spec)
        self.full = problem.com_model == COM_MODEL_FULL
        self.compliance = Compliance(spec) if self.full else None
        self.swing_sag = SwingLegSag(spec, problem.support) if self.full else None
        self.target = np.asarray(problem.target, dtype=float)[:, None]
        self.hand_row = row_of(problem.hand_point)
        first = ROW[f"{other_side(problem.support)}_foot_0"]
        self.swing_rows = slice(first, first + 4)
        self._plan: KernelPlan | None = None

    def kernel_plan(self) -> "KernelPlan | None":
        """This cost's constants for the compiled swarm kernel (:mod:`.kernel`), None where it does not apply
        (the projection model). Made once per model."""
        if self.problem.model != "dh":
            return None
        if self._plan is None:
            self._plan = self._build_kernel_plan()
        return self._plan

    def _build_kernel_plan(self) -> "KernelPlan":
        from op2motion.posture.kernel_plan import kernel_plan

        consts = {"penalty": PENALTY, "w_violation": W_VIOLATION, "w_margin": W_MARGIN, "margin_cap_m": MARGIN_CAP_M,
                  "w_upright": W_UPRIGHT, "sag_tilt_limit_rad": SAG_TILT_LIMIT_RAD,
                  "self_clearance_m": SELF_CLEARANCE_M, "lifted_m": LIFTED_M, "floor_tolerance_m": FLOOR_TOLERANCE_M,
                  "gravity_m_s2": GRAVITY_M_S2}
        return kernel_plan(self.spec, self.problem.support, self.problem.hand_point, self.target, self.extents,
                           self.full, consts)

    def __call__(self, angles: BookAngles, only_below: np.ndarray | None = None) -> CostTerms:
        """All cost terms for a batch of poses (book variables, support = the problem's): on the D-H model by the
        compiled kernel (clearances exact below :data:`CLEARANCE_EXACT_M`), else by :meth:`reference`."""
        plan = self.kernel_plan()
        if plan is None or angles.support != self.problem.support:
            return self.reference(angles, only_below)
        from op2motion.posture.kernel import swarm_terms

        terms = swarm_terms(plan, angles.vector(), only_below, CLEARANCE_EXACT_M)
        return CostTerms(*terms.T)

    def reference(self, angles: BookAngles, only_below: np.ndarray | None = None) -> CostTerms:
        """All cost terms for a batch of poses in NumPy (the reference the compiled kernel is tested against).

        ``only_below`` (N,) skips the self-collision check of the poses whose other terms already cost at least
        that much (a PSO particle that cannot beat its personal best): their ``collision`` is 0 and their
        ``clearance`` NaN, so their total is a lower bound. The penalty is never negative, so a swarm sees the
        same improvements as with every pose checked.
        """
        if self.problem.model == "dh" and angles.n < MATRIX_BELOW:     # one chain evaluation for points and links
            points, frames = forward_dh_frames(angles, self.spec, full_com=self.full)
        else:
            points = forward(angles, self.spec, self.problem.model, full_com=self.full)
            frames = matrix_frames(angles.vector(), self.spec, angles.support)     # the real body's links
        data = points.data
        hand = data[self.hand_row] - self.target
        hand_error = np.sqrt(np.einsum("in,in->n", hand, hand))
        swing_min_z = data[self.swing_rows, 2].min(axis=0)
        if self.compliance is not None and self.swing_sag is not None:   # the body physics simulates: full inertia
            settled = self.compliance.settle(points, points.full())
            com_xy, sag_tilt = settled.com_xy, settled.tilt      # infinite where no equilibrium exists
            corners = data[self.swing_rows]
            lowered = (self.compliance.settled_heights(points, settled, corners)
                       + self.swing_sag.heights(frames, corners)).min(axis=0)
            swing_lift = np.where(np.isfinite(lowered), lowered, swing_min_z) - LIFTED_M
        else:                             # the book's body: lumped masses on rigid joints
            com_xy, sag_tilt = points.com[:2], np.zeros(points.n)
            swing_lift = swing_min_z + FLOOR_TOLERANCE_M
        margin = rectangle_margin(com_xy[0], com_xy[1], self.extents)  # world = support frame
        sag_excess = np.maximum(np.minimum(sag_tilt, 1.0) - SAG_TILT_LIMIT_RAD, 0.0)
        # The book's penalties (code 2.8, 2.9): PenaltyStability is 100 exactly where the margin is negative; on
        # compliant servos also where the load would turn the torso over the limit.
        below = swing_lift < 0.0
        unstable = (margin < 0.0) | (sag_excess > 0.0)
        book_cost = np.where(below, PENALTY, 0.0) + np.where(unstable, PENALTY, 0.0) + hand_error
        # Beyond the book: a slope inside the penalised region leads a swarm that starts there out of it.
        slope = W_VIOLATION * (np.where(below, -swing_lift, 0.0) + np.minimum(np.maximum(-margin, 0.0), 1.0)
                               + 0.1 * sag_excess)
        axes = torso_axes(data, self.spec)
        tilt = torso_tilt(points, self.spec, axes)
        total = (book_cost + slope + W_MARGIN * (MARGIN_CAP_M - np.minimum(margin, MARGIN_CAP_M))
                 + W_UPRIGHT * tilt * tilt)
        collision, clearance = np.zeros(points.n), np.full(points.n, np.nan)
        check = np.ones(points.n, dtype=bool) if only_below is None else total < only_below
        if np.any(check):
            collision[check], clearance[check] = self_collision_penalty(frames[:, check], self.spec, angles.support)
        total = total + collision
        return CostTerms(total, book_cost, hand_error, margin, swing_min_z, tilt, collision, sag_tilt, clearance,
                         swing_lift)


def evaluate_cost(angles: BookAngles, problem: PostureProblem, spec: Spec) -> CostTerms:
    """All cost terms for a batch of poses (book variables, support = problem.support)."""
    return CostModel(problem, spec)(angles)
