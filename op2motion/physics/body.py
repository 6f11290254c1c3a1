"""The robot's state measured the same way for every engine, and where a pose starts on the floor.

An engine reports only the torso (``body_link``) pose and the 20 joint angles; :class:`Body` turns them into the
full-inertia centre of mass, the sole frames and the corners of both foot boxes with pinocchio on the generated
URDF, so both engines are judged by one piece of code. The feet are the spec's foot collision boxes (the real
soles, 105 x 66 mm), not the book's support rectangle.

:func:`placement` puts a pose on the floor: the support sole flat at the origin (X forward, Y left); in double
support the lower, more level sole is laid flat (the one that leaves the other foot at or above the floor, its
lowest corner touching when the soles are parallel); then the robot is lifted if any foot corner would start
below the floor, so nothing starts inside the ground. :func:`lying_placement` lays a pose on the floor instead: face
down, face up or on a side, its lowest collision shape touching the floor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from op2motion.errors import InputError
from op2motion.model.dynamics import dynamics_for
from op2motion.model.urdf import foot_box_corners, foot_link
from op2motion.robot.balance import point_margin
from op2motion.robot.spec import Collision, Spec, rpy_matrix
from op2motion.robot.support import SIDES, Side, Support, SupportName

GROUND_TOLERANCE_M = 1e-9
#: How a run may start lying, and the torso's rotation for each: face down (``front``: the torso's x axis, its front,
#: points down), face up (``back``), or on its ``left`` or ``right`` side (that side's y axis points down).
LYING = {"front": ((0.0, 1.0, 0.0), 0.5 * np.pi), "back": ((0.0, 1.0, 0.0), -0.5 * np.pi),
         "left": ((1.0, 0.0, 0.0), -0.5 * np.pi), "right": ((1.0, 0.0, 0.0), 0.5 * np.pi)}


@dataclass(frozen=True)
class BodyState:
    """Measured state [m] in the world (floor) frame."""

    com: np.ndarray                         # (3,) full-inertia centre of mass
    soles: dict[str, tuple[np.ndarray, np.ndarray]]   # side -> (position (3,), rotation (3, 3)) of the sole frame
    corners: dict[str, np.ndarray]          # side -> (4, 3) bottom corners of the foot box

    @property
    def lowest_corner_z(self) -> float:
        """Height of the lowest foot corner [m]."""
        return float(min(c[:, 2].min() for c in self.corners.values()))


class Body:
    """Pinocchio evaluation of the generated URDF for a torso pose and joint angles."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.dyn = dynamics_for(spec)
        self.pin = self.dyn.pin
        self.local_corners = {side: foot_box_corners(spec, side) for side in SIDES}
        # the corners with a 1 appended, so one product with a frame's 4 x 4 transform places them
        self._corners_h = {side: np.hstack([c, np.ones((len(c), 1))]) for side, c in self.local_corners.items()}
        self.foot_ids = {side: self.dyn.model.getFrameId(foot_link(spec, side)) for side in SIDES}
        self.foot_links = {side: foot_link(spec, side) for side in SIDES}

    def _configuration(self, base_pos: np.ndarray, base_rot: np.ndarray, q: np.ndarray) -> np.ndarray:
        config = self.dyn.configuration(q)
        config[:3] = base_pos
        config[3:7] = self.pin.Quaternion(np.asarray(base_rot, dtype=float)).coeffs()   # x, y, z, w
        return config

    def state(self, base_pos: np.ndarray, base_rot: np.ndarray, q: np.ndarray) -> BodyState:
        """The measured state for the torso frame at (``base_pos``, ``base_rot``) and joint angles ``q`` [rad]."""
        pin, model, data = self.pin, self.dyn.model, self.dyn.data
        config = self._configuration(base_pos, base_rot, q)
        com = pin.centerOfMass(model, data, config).copy()
        pin.updateFramePlacements(model, data)
        soles, corners, frames = {}, {}, data.oMf
        for side in SIDES:
            sole = frames[self.dyn.sole_ids[side]]
            soles[side] = (sole.translation.copy(), sole.rotation.copy())
            corners[side] = (self._corners_h[side] @ frames[self.foot_ids[side]].homogeneous.T)[:, :3]
        return BodyState(com, soles, corners)


def sole_flat(body: Body, q: np.ndarray, side: Side) -> tuple[np.ndarray, np.ndarray]:
    """Torso pose (position, rotation) that puts the ``side`` sole at the origin, level, facing +X."""
    state = body.state(np.zeros(3), np.eye(3), q)
    pos, rot = state.soles[side]
    base_rot = rot.T                       # sole frame -> world identity
    return -base_rot @ pos, base_rot


@dataclass(frozen=True)
class Placement:
    """Where a pose starts: the torso's position ``pos`` [m] and rotation ``rot`` (world frame), the sole laid level
    (``flat``), and the settling gap [m]: how high the supporting foot that does not touch starts above the floor
    (0 when every supporting foot touches)."""

    pos: np.ndarray
    rot: np.ndarray
    flat: Side
    gap: float


def placement(body: Body, q: np.ndarray, support: Support | SupportName) -> Placement:
    """Where a pose starts (:class:`Placement`; see the module docstring)."""
    options = []
    for side in Support.of(support).feet:
        pos, rot = sole_flat(body, q, side)
        state = body.state(pos, rot, q)
        lift = max(0.0, -state.lowest_corner_z)      # nothing starts below the floor
        gap = max(float(state.corners[s][:, 2].min()) + lift for s in Support.of(support).feet)
        options.append((gap, side, pos + np.array([0.0, 0.0, lift]), rot))
    gap, side, pos, rot = min(options, key=lambda o: o[0])   # the lower, more level sole: the smallest gap
    return Placement(pos, rot, side, gap)


def margin_to(state: BodyState, support: Support, xy: np.ndarray) -> float:
    """Margin [m] of a point (2,) to the support polygon of ``support`` in ``state`` (positive inside)."""
    return point_margin(float(xy[0]), float(xy[1]), support.polygon(state.corners))


def _axis_rotation(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    """The rotation (3, 3) by ``angle`` [rad] about a unit ``axis``."""
    a = np.asarray(axis, dtype=float)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    rotation: np.ndarray = np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)
    return rotation


def shape_bottom(shape: Collision, link_pos: np.ndarray, link_rot: np.ndarray) -> float:
    """The lowest world z [m] of a collision shape on a link placed at (``link_pos``, ``link_rot``)."""
    rot = link_rot @ rpy_matrix(shape.origin_rpy)
    centre = link_pos + link_rot @ np.asarray(shape.origin_xyz, dtype=float)
    if shape.shape == "sphere":
        return float(centre[2] - shape.size[0])
    if shape.shape == "cylinder":
        radius, length = shape.size
        up = abs(float(rot[2, 2]))                      # vertical share of the cylinder's axis
        return float(centre[2] - 0.5 * length * up - radius * np.sqrt(max(0.0, 1.0 - up * up)))
    half = 0.5 * np.asarray(shape.size, dtype=float)
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    return float((centre + (signs * half) @ rot.T)[:, 2].min())


def lowest_point(body: Body, base_pos: np.ndarray, base_rot: np.ndarray, q: np.ndarray) -> float:
    """The lowest world z [m] of any collision shape of the robot at that torso pose and joint angles [rad]."""
    pin, model, data = body.pin, body.dyn.model, body.dyn.data
    pin.framesForwardKinematics(model, data, body._configuration(base_pos, base_rot, q))
    out = np.inf
    for shape in body.spec.collisions:
        frame = data.oMf[model.getFrameId(shape.link)]
        out = min(out, shape_bottom(shape, frame.translation, frame.rotation))
    return float(out)


def lying_placement(body: Body, q: np.ndarray, lying: str) -> tuple[np.ndarray, np.ndarray]:
    """Where a pose starts lying (:data:`LYING`: ``front``, ``back``, ``left`` or ``right``): torso (position [m],
    rotation), its lowest collision shape just touching the floor."""
    if lying not in LYING:
        raise InputError(f"expected one of {', '.join(LYING)}, got {lying!r}", "lying")
    rot = _axis_rotation(*LYING[lying])
    bottom = lowest_point(body, np.zeros(3), rot, q)
    return np.array([0.0, 0.0, -bottom + GROUND_TOLERANCE_M]), rot
