"""Is a whole-body state allowed along a motion: what the joint-space planner (:mod:`.route`) checks, in batches.

For poses (N, 20) [rad] standing on one foot (``side``) or both (``side`` None), measured in the stance sole's
frame (world = support foot: X forward, Y left, Z up):

* ``clearance`` [m]: the least distance between the spec's collision shapes (the ones physics simulates) on the
  D-H chain, by the compiled swarm kernel (exact below :data:`~op2motion.posture.cost.CLEARANCE_EXACT_M`);
* ``margin`` [m]: on one foot, the settled full-inertia CoM (the compliant servos' sag) to the sole's edge; on both,
  the full-inertia CoM to the hull of both soles;
* ``floor`` [m]: the lowest of the points that must stay off the floor (hands, elbows, knees, head, pelvis);
* ``swing`` [m]: on one foot, the other foot's lowest corner after the sag, less
  :data:`~op2motion.robot.support.LIFTED_M` (>= 0: lifted); +inf on both feet;
* ``tilt`` [rad]: on one foot, how far the torso turns as the servos take the load; 0 on both.

:class:`Limits` are the least values allowed: the planner's own (:data:`PLAN_CLEARANCE_M` and so on), lowered to
a segment's ends where an end itself has less, so that a motion between two poses is never refused for what its
ends already are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.kinematics import forward
from op2motion.kinematics.points import ROW
from op2motion.posture.cost import SAG_TILT_LIMIT_RAD, SELF_CLEARANCE_M, CostModel, PostureProblem
from op2motion.robot.balance import polygon_margin
from op2motion.robot.joints import joint_range, servo_to_book
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support, as_side

ROUTE_SLACK_M = 0.002      # planned paths keep this much more than SELF_CLEARANCE_M: smoothing and balance leans
PLAN_CLEARANCE_M = SELF_CLEARANCE_M + ROUTE_SLACK_M
PLAN_MARGIN_M = 0.005      # the CoM stays this far inside the support along a planned path
FLOOR_CLEAR_M = 0.02       # points off the floor by this much: the collision shapes reach about 20 mm past them
OFF_FLOOR = ("left_hand", "right_hand", "l_el", "r_el", "l_knee", "r_knee", "head_top", "pelvis")
_ANY_HAND_TARGET = (0.0, 0.0, 0.2)   # the cost model needs a hand target; its hand term is not used here


@dataclass(frozen=True)
class Measures:
    """Per pose (N,): clearance [m], CoM margin [m], lowest off-floor point [m], swing-foot lift [m], sag tilt
    [rad] (see the module docstring)."""

    clearance: np.ndarray
    margin: np.ndarray
    floor: np.ndarray
    swing: np.ndarray
    tilt: np.ndarray

    def least(self) -> "Limits":
        """The smallest clearance, margin, floor and swing and the largest tilt over these poses."""
        return Limits(float(np.min(self.clearance)), float(np.min(self.margin)), float(np.min(self.floor)),
                      float(np.min(self.swing)), float(np.max(self.tilt)))


@dataclass(frozen=True)
class Limits:
    """The least clearance, margin, floor height, swing lift [m] and the largest tilt [rad] a state may have."""

    clearance: float = PLAN_CLEARANCE_M
    margin: float = PLAN_MARGIN_M
    floor: float = FLOOR_CLEAR_M
    swing: float = 0.0
    tilt: float = SAG_TILT_LIMIT_RAD

    def relaxed_to(self, ends: "Limits") -> "Limits":
        """These limits lowered (the tilt raised) to what a segment's ends have."""
        return Limits(min(self.clearance, ends.clearance), min(self.margin, ends.margin), min(self.floor, ends.floor),
                      min(self.swing, ends.swing), max(self.tilt, ends.tilt))

    def allows(self, m: Measures) -> np.ndarray:
        """Which poses (N,) keep every limit."""
        return ((m.clearance >= self.clearance) & (m.margin >= self.margin) & (m.floor >= self.floor)
                & (m.swing >= self.swing) & (m.tilt <= self.tilt))


def body_cost(spec: Spec, stance: Support | Side) -> CostModel:
    """The posture cost standing on ``stance`` (full sole, full-inertia CoM), used for what it measures beside the
    hand: clearance between links, the settled CoM's margin, the swing foot's lift, the sag tilt."""
    return CostModel(PostureProblem(as_side(stance, "support"), "left", _ANY_HAND_TARGET, 1.0), spec)


class BodyChecks:
    """The measures of poses standing on ``side`` (``left``/``right``) or on both feet (None), prepared once."""

    def __init__(self, spec: Spec, side: Support | Side | None):
        self.spec, self.side = spec, side
        self.frame = side or "left"
        self.cost = body_cost(spec, self.frame)
        lower, upper = zip(*(joint_range(j, "mechanical") for j in spec.joints))
        self.lower, self.upper = np.array(lower), np.array(upper)

    def measure(self, servo: np.ndarray) -> Measures:
        """Every measure of poses ``servo`` (N, 20) [rad]."""
        servo = np.atleast_2d(servo)
        angles = servo_to_book(servo, self.frame, self.spec)
        terms = self.cost(angles)
        points = forward(angles, self.spec, "dh", full_com=self.side is None)
        rows = [ROW[n] for n in OFF_FLOOR if n in ROW] or [ROW["pelvis"]]
        floor = points.data[rows, 2].min(axis=0)
        n = len(servo)
        if self.side is None:
            hull = Support.DOUBLE.polygon({s: points.foot_corners(s)[0] for s in ("left", "right")})
            margin = polygon_margin(points.full()[:2].T, hull)
            return Measures(terms.clearance, margin, floor, np.full(n, np.inf), np.zeros(n))
        return Measures(terms.clearance, terms.margin, floor, terms.swing_lift, terms.sag_tilt)

    def within_joint_limits(self, servo: np.ndarray) -> np.ndarray:
        """Which poses (N,) keep every joint inside its mechanical range."""
        servo = np.atleast_2d(servo)
        within: np.ndarray = np.all((servo >= self.lower - 1e-9) & (servo <= self.upper + 1e-9), axis=1)
        return within
