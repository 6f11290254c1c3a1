"""Test oracle: forward kinematics of the official ROBOTIS description straight from the spec's joint table.

It walks the URDF-style tree (origin xyz, rpy, axis per joint) from the torso with the servo angles, entirely
independently of the book's D-H chain, and expresses every point in the support sole frame.
"""

from __future__ import annotations

import math

import numpy as np

from op2motion.robot.spec import Spec


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _axis_angle(axis, q: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(q) * k + (1 - math.cos(q)) * k @ k


def official_points(servo: np.ndarray, spec: Spec, support: str) -> dict[str, np.ndarray]:
    """Joint centres, hands, head top and soles for one servo vector (rad, ID order), in the support sole frame."""
    q = dict(zip(spec.joint_names, servo))
    frames = {spec.root_link: (np.eye(3), np.zeros(3))}
    joint_origin = {}
    pending = list(spec.joints)
    while pending:
        for j in list(pending):
            if j.parent in frames:
                rp, pp = frames[j.parent]
                rj, pj = rp @ _rpy(*j.origin_rpy), pp + rp @ np.array(j.origin_xyz)
                joint_origin[j.name] = pj
                frames[j.child] = (rj @ _axis_angle(j.axis, q[j.name]), pj)
                pending.remove(j)
    pts = dict(joint_origin)
    for name, point in spec.points.items():
        r, p = frames[point.link]
        pts[name] = p + r @ np.array(point.xyz)
    for side, link in (("left", "l_ank_roll_link"), ("right", "r_ank_roll_link")):
        r, p = frames[link]
        pts[f"{side}_sole"] = p + r @ np.array([0.0, 0.0, -spec.foot.sole_below_ankle])
        frames[f"{side}_sole"] = (r, pts[f"{side}_sole"])
    r_s, p_s = frames[f"{support}_sole"]
    return {k: r_s.T @ (v - p_s) for k, v in pts.items()}
