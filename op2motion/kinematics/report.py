"""One pose evaluated for people and JSON: body points, CoM, hands, swing foot, stability margin, servo angles."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from op2motion.errors import InputError, LimitViolation
from op2motion.jsonout import JsonObject
from op2motion.kinematics import BodyPoints, ModelName, forward
from op2motion.robot.balance import COM_MODEL_FULL, check_br, polygon_margin, stability_margin
from op2motion.robot.joints import (
    BookAngles,
    book_to_servo,
    limit_violations,
    servo_dict,
    servo_to_ticks,
)
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support


def _vec(v: np.ndarray) -> list[float]:
    return [float(x) for x in v]


@dataclass(frozen=True)
class PoseReport:
    """Forward kinematics and balance of one pose on one model; lengths [m] in the world frame (support sole
    centre, X forward, Y left, Z up; moved to ``sp`` and turned by ``gamma`` when given)."""

    model: ModelName
    support: Support
    points: BodyPoints
    com: np.ndarray
    br: float
    stability_margin_m: float
    com_full: np.ndarray
    stability_margin_full_m: float
    servo: np.ndarray
    book: BookAngles
    ticks: dict[str, int] | None
    limit_violations: list[LimitViolation]
    double: bool = False

    @property
    def double_support_margin_m(self) -> float:
        """Margin [m] of the full-inertia CoM to the convex hull of both soles (a pose standing on both feet)."""
        hull = Support.DOUBLE.polygon({s: self.points.foot_corners(s)[0] for s in ("left", "right")})
        return float(polygon_margin(self.com_full[:2], hull)[0])

    @property
    def swing_foot_min_z(self) -> float:
        """Height of the swing foot's lowest corner [m]."""
        return float(self.points.swing_foot_min_z[0])

    def as_dict(self, spec: Spec) -> JsonObject:
        """JSON-ready dict (the ``fk --json`` keys)."""
        double: JsonObject = {"frame": f"{self.support} sole", "double_support_margin_m": self.double_support_margin_m}
        return {
            "model": self.model, "support": "double" if self.double else self.support,
            **(double if self.double else {}), "points": self.points.as_dict(0), "com": _vec(self.com),
            "com_model": "book", "com_full": _vec(self.com_full),
            "stability_margin_full_m": self.stability_margin_full_m,
            "left_hand": _vec(self.points.point("left_hand")[0]),
            "right_hand": _vec(self.points.point("right_hand")[0]),
            "swing_foot_corners": [_vec(c) for c in self.points.swing_foot_corners[0]],
            "swing_foot_min_z": self.swing_foot_min_z, "br": self.br, "stability_margin_m": self.stability_margin_m,
            "servo_deg": servo_dict(self.servo, spec), "book_deg": self.book.degrees(), "ticks": self.ticks,
            "limit_violations": [v.as_dict() for v in self.limit_violations],
        }

    def human(self) -> str:
        """A short multi-line text summary."""
        def fmt(v: Iterable[float]) -> str:
            return "(" + ", ".join(f"{x:+.4f}" for x in v) + ")"

        margin = (f"stability margin {self.double_support_margin_m * 1000:+.1f} mm full inertia, to the hull of both "
                  f"soles (positive = inside)" if self.double else
                  f"stability margin {self.stability_margin_m * 1000:+.1f} mm lumped, "
                  f"{self.stability_margin_full_m * 1000:+.1f} mm full inertia (br {self.br}; positive = inside)")
        lines = [
            f"model {self.model.upper()}, " + (f"double support (frame: the {self.support} sole)" if self.double
                                               else f"{self.support} support"),
            f"centre of mass   {fmt(self.com)} m  [lumped, the book's masses]",
            f"                 {fmt(self.com_full)} m  [full inertia, the spec's link inertials]",
            margin,
            f"left hand        {fmt(self.points.point('left_hand')[0])} m",
            f"right hand       {fmt(self.points.point('right_hand')[0])} m",
        ]
        if not self.double:
            lines.append(f"swing foot lowest corner z {self.swing_foot_min_z * 1000:+.2f} mm")
        lines += [f"warning: {v.describe()}" for v in self.limit_violations]
        return "\n".join(lines)


def pose_report(angles: BookAngles, spec: Spec, model: ModelName = "dh", br: float = 1.0,
             sp: Sequence[float] = (0.0, 0.0, 0.0), gamma: float = 0.0, double: bool = False) -> PoseReport:
    """Forward kinematics and balance of the first pose of ``angles`` (``double``: standing on both feet, measured
    in the support sole's frame, its margin to the hull of both soles)."""
    one = angles.row(0)
    points = forward(one, spec, model, sp, gamma)
    com = points.com[:, 0].copy()
    margin = float(stability_margin(com[None, :2], spec, one.support.stance, check_br(br), (sp[0], sp[1]), gamma)[0])
    servo = book_to_servo(one, spec)[0]
    full = forward(one, spec, "dh", sp, gamma, full_com=True).full()[:, 0].copy()   # true geometry, any model
    margin_full = float(stability_margin(full[None, :2], spec, one.support.stance, br, (sp[0], sp[1]), gamma,
                                         COM_MODEL_FULL)[0])
    try:
        ticks: dict[str, int] | None = {str(j.id): int(t) for j, t in zip(spec.joints, servo_to_ticks(servo, spec))}
    except InputError:  # an angle beyond ±180° has no tick; limit_violations names it
        ticks = None
    violations = limit_violations(servo, spec, "mechanical") + limit_violations(servo, spec, "cable-safe")
    return PoseReport(model, one.support, points, com, br, margin, full, margin_full, servo, one, ticks, violations,
                      double)
