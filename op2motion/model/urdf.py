"""The OP2 URDF, generated from the spec (never hand-edited).

Root link ``base_link``, carrying the torso ``body_link`` (origin as in the official description) on a fixed joint,
as ROS tools (robot_state_publisher, RViz) expect; the 20 revolute joints with the official names, origins, axes
and zero offsets, mechanical limits (the stops), MX-28 effort and velocity; an ``<inertial>`` on every link (the
Webots masses, CoMs and tensors re-expressed in our link frames); simple collision shapes (spec ``[[collision]]``);
and named frames for the spec's points and the two soles as fixed child links.

Frame links carry a tiny inertial (:data:`FRAME_LINK_MASS_KG`): a link without one would become 1 kg in PyBullet.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.spec import Collision, Inertial, Spec
from op2motion.robot.support import Side, Support

FRAME_LINK_MASS_KG = 1e-5      # named frames (hands, soles, ...): tiny mass so no tool invents 1 kg for them
FRAME_LINK_INERTIA = 1e-10     # [kg·m²]
ROBOT_NAME = "robotis_op2"
_COLOURS = {"left": ("left_blue", "0.25 0.45 0.85 1"), "right": ("right_red", "0.85 0.3 0.25 1"),
            "body": ("body_ivory", "0.93 0.91 0.84 1")}  # left/right as in op2motion's plots; the OP2 is ivory


@dataclass(frozen=True)
class LinkInertial:
    """Mass [kg], CoM [m] and inertia tensor about the CoM [kg·m²], all in our link frame."""

    mass: float
    com: np.ndarray
    tensor: np.ndarray


def link_inertial(item: Inertial) -> LinkInertial:
    """A spec inertial as arrays (link frame)."""
    return LinkInertial(item.mass, item.link_com, item.link_tensor)


URDF_ROOT = "base_link"     # the root ROS tools expect; a fixed joint carries the torso (``body_link``)
FRAME_SUFFIX = "_link"


def sole_link(side: Side) -> str:
    """The URDF link at the centre of the ``left`` or ``right`` sole."""
    return f"{side}_sole{FRAME_SUFFIX}"


def frame_link(spec: Spec, name: str) -> str:
    """The URDF link of a named point or sole (``left_hand`` -> ``left_hand_link``, ``camera`` -> ``head_cam``)."""
    if name in spec.points:
        return spec.points[name].frame
    if name in ("left_sole", "right_sole"):
        return sole_link("left" if name == "left_sole" else "right")
    raise InputError(f"expected a named point ({', '.join(spec.points)}) or a sole, got {name!r}", "frame")


def foot_link(spec: Spec, side: Support | Side) -> str:
    """The URDF link that carries the ``left`` or ``right`` foot (the ankle-roll joint's child)."""
    return spec.joint(f"{side[0]}_ank_roll").child


def foot_box_corners(spec: Spec, side: Support | Side) -> np.ndarray:
    """The 4 bottom corners (4, 3) [m] of a foot's collision box in its ankle-roll link frame (the sole)."""
    link = foot_link(spec, side)
    boxes = spec.collisions_of(link, "box")
    if not boxes:
        raise InputError(f"the spec has no box collision shape on {link}: the foot's sole is unknown", "spec")
    box = boxes[0]
    if any(abs(a) > 1e-12 for a in box.origin_rpy):
        raise InputError(f"the foot box on {link} must not be rotated", "spec")
    (sx, sy, sz), (ox, oy, oz) = box.size, box.origin_xyz
    return np.array([[ox + dx * sx / 2, oy + dy * sy / 2, oz - sz / 2]
                     for dx, dy in ((1, 1), (1, -1), (-1, -1), (-1, 1))])


def frame_points(spec: Spec) -> dict[str, tuple[str, str, tuple[float, float, float]]]:
    """Named frames: ``{point name: (frame link, parent link, xyz [m])}`` for the spec's points and both soles."""
    frames = {name: (p.frame, p.link, p.xyz) for name, p in spec.points.items()}
    for side in ("left", "right"):
        frames[f"{side}_sole"] = (sole_link(side), foot_link(spec, side), (0.0, 0.0, -spec.foot.sole_below_ankle))
    return frames


def _f(v: float) -> str:
    return f"{v:.9g}"


def _vec(v: Iterable[float]) -> str:
    return " ".join(_f(float(x)) for x in v)


def _inertial_xml(inertial: LinkInertial) -> str:
    t = inertial.tensor
    return (f'    <inertial>\n      <origin xyz="{_vec(inertial.com)}" rpy="0 0 0"/>\n'
            f'      <mass value="{_f(inertial.mass)}"/>\n'
            f'      <inertia ixx="{_f(t[0, 0])}" ixy="{_f(t[0, 1])}" ixz="{_f(t[0, 2])}" iyy="{_f(t[1, 1])}" '
            f'iyz="{_f(t[1, 2])}" izz="{_f(t[2, 2])}"/>\n    </inertial>\n')


def build_urdf(spec: Spec) -> str:
    """The URDF text of the robot described by ``spec``."""
    # here, not at import: it loads urllib, http and email (40 ms) for every importer of this module
    from xml.sax.saxutils import quoteattr

    inertials = {i.link: link_inertial(i) for i in spec.inertials}
    collisions: dict[str, list[Collision]] = {}
    for c in spec.collisions:
        collisions.setdefault(c.link, []).append(c)
    links = [spec.root_link] + [j.child for j in spec.joints]
    frame_inertial = _inertial_xml(LinkInertial(FRAME_LINK_MASS_KG, np.zeros(3), np.eye(3) * FRAME_LINK_INERTIA))
    out = [f'<?xml version="1.0"?>\n<!-- Generated by op2motion from {spec.path} (sha256 {spec.sha256[:16]}); '
           f'do not edit. -->\n<robot name={quoteattr(ROBOT_NAME)}>\n',
           f"  <link name={quoteattr(URDF_ROOT)}>\n{frame_inertial}  </link>\n"
           f"  <joint name=\"base_joint\" type=\"fixed\">\n    <parent link={quoteattr(URDF_ROOT)}/>\n"
           f"    <child link={quoteattr(spec.root_link)}/>\n    <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n  </joint>\n"]
    for link in links:
        out.append(f"  <link name={quoteattr(link)}>\n")
        if link in inertials:
            out.append(_inertial_xml(inertials[link]))
        else:
            out.append(_inertial_xml(LinkInertial(FRAME_LINK_MASS_KG, np.zeros(3), np.eye(3) * FRAME_LINK_INERTIA)))
        for c in collisions.get(link, []):
            if c.shape == "box":
                geom = f'<box size="{_vec(c.size)}"/>'
            elif c.shape == "cylinder":
                geom = f'<cylinder radius="{_f(c.size[0])}" length="{_f(c.size[1])}"/>'
            else:
                geom = f'<sphere radius="{_f(c.size[0])}"/>'
            origin = f'<origin xyz="{_vec(c.origin_xyz)}" rpy="{_vec(c.origin_rpy)}"/>'
            colour = _COLOURS["left" if link.startswith("l_") else "right" if link.startswith("r_") else "body"]
            out.append(f"    <visual>\n      {origin}\n      <geometry>{geom}</geometry>\n"
                       f'      <material name="{colour[0]}"><color rgba="{colour[1]}"/></material>\n    </visual>\n'
                       f"    <collision>\n      {origin}\n      <geometry>{geom}</geometry>\n    </collision>\n")
        out.append("  </link>\n")
    effort, velocity = spec.servo.stall_torque_nm, spec.servo.no_load_speed_rad_s
    for j in spec.joints:
        out.append(f'  <joint name={quoteattr(j.name)} type="revolute">\n'
                   f"    <parent link={quoteattr(j.parent)}/>\n    <child link={quoteattr(j.child)}/>\n"
                   f'    <origin xyz="{_vec(j.origin_xyz)}" rpy="{_vec(j.origin_rpy)}"/>\n'
                   f'    <axis xyz="{_vec(j.axis)}"/>\n'
                   f'    <limit lower="{_f(j.mechanical[0])}" upper="{_f(j.mechanical[1])}" effort="{_f(effort)}" '
                   f'velocity="{_f(velocity)}"/>\n  </joint>\n')
    for name, (link, parent, xyz) in frame_points(spec).items():
        out.append(f"  <link name={quoteattr(link)}>\n{frame_inertial}  </link>\n"
                   f"  <joint name={quoteattr(name + '_joint')} type=\"fixed\">\n"
                   f"    <parent link={quoteattr(parent)}/>\n    <child link={quoteattr(link)}/>\n"
                   f'    <origin xyz="{_vec(xyz)}" rpy="0 0 0"/>\n  </joint>\n')
    out.append("</robot>\n")
    return "".join(out)


def total_mass(spec: Spec) -> float:
    """Mass of the URDF robot [kg] (Webots link masses plus the tiny frame links)."""
    return sum(i.mass for i in spec.inertials) + FRAME_LINK_MASS_KG * (
        1 + len(frame_points(spec)) + len({spec.root_link} | {j.child for j in spec.joints}) - len(spec.inertials))
