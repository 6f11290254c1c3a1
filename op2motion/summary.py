"""Evaluate one pose for people and for ``--json``: body points, CoM, hands, swing foot, margin, servo angles."""

from __future__ import annotations

from typing import Any, Sequence

from .balance import COM_MODEL_LUMPED, com_lumped, stability_margin
from .errors import InputError
from .joints import BookAngles, book_to_servo, limit_violations, servo_dict, servo_to_ticks
from .kinematics import BodyPoints, forward
from .spec import Spec


def evaluate(angles: BookAngles, spec: Spec, model: str = "dh", br: float = 1.0,
             sp: Sequence[float] = (0.0, 0.0, 0.0), gamma: float = 0.0) -> tuple[BodyPoints, dict[str, Any]]:
    """Forward kinematics and balance of the first pose of ``angles``; returns the points and a JSON-ready dict."""
    one = angles.row(0)
    points = forward(one, spec, model, sp, gamma)
    com = com_lumped(points, spec)[0]
    margin = float(stability_margin(com[None, :2], spec, one.support, br, (sp[0], sp[1]), gamma)[0])
    servo = book_to_servo(one, spec)[0]
    result: dict[str, Any] = {
        "model": model,
        "support": one.support,
        "points": points.as_dict(0),
        "com": [float(v) for v in com],
        "com_model": COM_MODEL_LUMPED,
        "left_hand": [float(v) for v in points.point("left_hand")[0]],
        "right_hand": [float(v) for v in points.point("right_hand")[0]],
        "swing_foot_corners": [[float(v) for v in c] for c in points.swing_foot_corners[0]],
        "swing_foot_min_z": float(points.swing_foot_min_z[0]),
        "br": br,
        "stability_margin_m": margin,
        "servo_deg": servo_dict(servo, spec),
        "book_deg": one.degrees(),
        "limit_violations": limit_violations(servo, spec),
    }
    try:
        result["ticks"] = {str(j.id): int(t) for j, t in zip(spec.joints, servo_to_ticks(servo, spec))}
    except InputError:  # an angle beyond ±180° has no tick; limit_violations already names it
        result["ticks"] = None
    return points, result


def human(result: dict[str, Any]) -> str:
    """A short multi-line text summary of :func:`evaluate`'s result."""
    fmt = lambda v: "(" + ", ".join(f"{x:+.4f}" for x in v) + ")"  # noqa: E731
    lines = [
        f"model {result['model'].upper()}, {result['support']} support",
        f"centre of mass   {fmt(result['com'])} m  [{result['com_model']}]",
        f"stability margin {result['stability_margin_m'] * 1000:+.1f} mm (br {result['br']}; positive = inside)",
        f"left hand        {fmt(result['left_hand'])} m",
        f"right hand       {fmt(result['right_hand'])} m",
        f"swing foot lowest corner z {result['swing_foot_min_z'] * 1000:+.2f} mm",
    ]
    for v in result["limit_violations"]:
        lines.append(f"warning: {v['joint']} = {v['deg']:.1f}° outside its limits [{v['lower_deg']}, {v['upper_deg']}]°")
    return "\n".join(lines)
