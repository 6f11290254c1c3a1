"""The OP2 spec as frozen dataclasses: the single source of every robot number.

:mod:`op2motion.robot.specfile` reads and checks ``specs/op2.toml`` into a :class:`Spec`. :class:`Geometry` holds the
lengths the kinematic models use, derived from the official joint table so that no length is written twice.
Angles [rad], lengths [m], masses [kg], torques [N·m].
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from op2motion.errors import SpecError
from op2motion.robot.sides import Side

SCHEMA = "op2motion.spec/2"
GRAVITY_M_S2 = 9.81          # standard gravity, for every model of the robot
BOOK_VARS = tuple([f"th{i}" for i in range(1, 12)] + [f"phi{i}" for i in range(1, 7)]
                  + [f"psi{i}" for i in range(1, 4)])


@dataclass(frozen=True)
class BookMap:
    """How one servo angle follows from one book variable: ``servo = sign * var + offset`` [rad]."""

    var: str
    sign: int
    offset: float


@dataclass(frozen=True)
class Joint:
    """One servo joint as in the official ROBOTIS description (angles in rad, lengths in m)."""

    name: str
    id: int
    framework: str
    webots: str
    parent: str
    child: str
    origin_xyz: tuple[float, float, float]
    origin_rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    safe: tuple[float, float]
    mechanical: tuple[float, float]
    book: Mapping[str, BookMap]
    webots_range: tuple[float, float]     # the Webots model's motor stops [rad]

    @property
    def lower(self) -> float:
        """Lower end of the cable-safe range [rad] (advice: the optimiser's box)."""
        return self.safe[0]

    @property
    def upper(self) -> float:
        """Upper end of the cable-safe range [rad]."""
        return self.safe[1]


@dataclass(frozen=True)
class Rating:
    """The servo's rating at one supply voltage [V]: stall torque [N·m] and no-load speed [rad/s]."""

    voltage_v: float
    stall_torque_nm: float
    no_load_speed_rad_s: float


@dataclass(frozen=True)
class Servo:
    """Dynamixel MX-28 facts and the parameters of its physical model (see :mod:`op2motion.model.servo`)."""

    model: str
    ticks_per_rev: int
    center_tick: int
    min_tick: int
    max_tick: int
    framework_deg_per_tick: float
    invalid_bit: int
    torque_off_bit: int
    ratings: tuple[Rating, ...]
    supply_voltage_v: float
    p_gain_default: int
    duty_per_p_rad: float
    max_duty: float
    armature_kg_m2: float
    friction_nm: float
    viscous_nm_s_rad: float
    backlash_rad: float
    operating_voltage_v: tuple[float, float] = (10.0, 14.8)

    @property
    def rad_per_tick(self) -> float:
        """Exact angle of one tick [rad]."""
        return 2.0 * math.pi / self.ticks_per_rev

    @property
    def rating(self) -> Rating:
        """The rating at the supply voltage."""
        return next(r for r in self.ratings if r.voltage_v == self.supply_voltage_v)

    @property
    def stall_torque_nm(self) -> float:
        """Stall torque at the supply voltage [N·m]."""
        return self.rating.stall_torque_nm

    @property
    def no_load_speed_rad_s(self) -> float:
        """No-load speed at the supply voltage [rad/s]."""
        return self.rating.no_load_speed_rad_s


@dataclass(frozen=True)
class Foot:
    """Foot rectangle about the sole centre (below the ankle) [m], for the left foot; mirrored on the right."""

    sole_below_ankle: float
    front: float
    back: float
    inner: float
    outer: float

    def extents(self, side: Side, br: float = 1.0) -> tuple[float, float, float, float]:
        """(front, back, left, right) half-extents [m] of the ``side`` sole about its centre, shrunk by ``br``.

        The outer edge is on the left of the left foot and on the right of the right foot (book fig. 2.30).
        """
        left, right = (self.outer, self.inner) if side == "left" else (self.inner, self.outer)
        return br * self.front, br * self.back, br * left, br * right

    def corners(self, side: Side) -> tuple[tuple[float, float], ...]:
        """Sole corners (forward, left) [m] about the sole centre: front-left, front-right, back-right, back-left."""
        front, back, left, right = self.extents(side)
        return ((front, left), (front, -right), (-back, -right), (-back, left))


@dataclass(frozen=True)
class PointSpec:
    """A named point fixed to a link: ``xyz`` [m] in the frame of ``link``; ``frame`` names its URDF frame link."""

    link: str
    xyz: tuple[float, float, float]
    frame: str


@dataclass(frozen=True)
class LumpedMass:
    """A lumped mass [kg] at ``fraction`` of the way from body point ``start`` to body point ``end``."""

    name: str
    mass: float
    start: str
    end: str
    fraction: float


def rpy_matrix(rpy: tuple[float, float, float]) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw [rad] to a rotation matrix (Rz(yaw) Ry(pitch) Rx(roll))."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


@dataclass(frozen=True)
class Uncertainty:
    """How far a link's mass figures may be off (about 2σ): the mass by ±``mass_fraction`` of itself, the centre of
    mass by ``com_m`` = ((low, high) per axis x, y, z) [m] in the link frame (low <= 0 <= high)."""

    mass_fraction: float
    com_m: tuple[tuple[float, float], tuple[float, float], tuple[float, float]]


@dataclass(frozen=True)
class Inertial:
    """A link's mass [kg], centre of mass [m] and inertia tensor about the centre of mass (ixx, iyy, izz, ixy, ixz,
    iyz) [kg·m²] in the link frame; where each figure comes from (``sources``: figure -> key of the spec's
    ``[sources]`` table, for ``mass``, ``com`` and ``inertia``) and how far it may be off (None: not stated)."""

    link: str
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]
    sources: Mapping[str, str]
    uncertainty: Uncertainty | None

    @property
    def link_com(self) -> np.ndarray:
        """The centre of mass (3,) [m] in the link frame."""
        return np.asarray(self.com, dtype=float)

    @property
    def link_tensor(self) -> np.ndarray:
        """The inertia tensor about the centre of mass (3, 3) [kg·m²] in the link frame."""
        return inertia_matrix(self.inertia)


def inertia_matrix(six: tuple[float, ...]) -> np.ndarray:
    """The symmetric (3, 3) tensor [kg·m²] of (ixx, iyy, izz, ixy, ixz, iyz)."""
    ixx, iyy, izz, ixy, ixz, iyz = six
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


@dataclass(frozen=True)
class Collision:
    """A collision shape fixed to a link: ``box`` (size x, y, z), ``cylinder`` (radius, length along z) or
    ``sphere`` (radius) [m], at ``origin_xyz`` [m] / ``origin_rpy`` [rad] in the link frame."""

    link: str
    shape: str
    size: tuple[float, ...]
    origin_xyz: tuple[float, float, float]
    origin_rpy: tuple[float, float, float]


COLLISION_SIZES = {"box": 3, "cylinder": 2, "sphere": 1}


@dataclass(frozen=True)
class Geometry:
    """Lengths [m] the kinematic models use, derived from the joint table (left side; the right mirrors it)."""

    ankle_to_sole: float
    calf: float
    thigh: float
    hip_yaw_to_roll: float
    hip_half_width: float
    hip_x: float
    torso: float
    shoulder_half_width: float
    shoulder_roll_lateral: float
    shoulder_roll_drop: float
    elbow_forward: float
    upper_arm: float
    lower_arm: float
    head_pan_height: float
    head_tilt_height: float
    head_length: float


@dataclass(frozen=True)
class ImuChannel:
    """One IMU register of the sub-controller and what it measures in the torso frame: ``value = sign * (count -
    centre) * scale``, ``scale`` in rad/s (gyro) or m/s² (accelerometer) per count; ``axis`` 0 x, 1 y, 2 z; where
    the mapping comes from (``source``) and why (``reasoning``)."""

    sensor: str
    register: int
    axis: int
    sign: int
    scale: float
    source: str
    reasoning: str


@dataclass(frozen=True)
class ImuSpec:
    """The sub-controller's IMU on the bus (spec ``[imu]``): the board's ID, the counts' centre and top, the gyro
    and accelerometer channels by torso axis (x, y, z), the accelerometer's other stated scale [m/s² per count],
    and the framework's fall test: the fore-aft accelerometer count (the channel along x) averaged over
    ``fallen_window`` samples below ``fallen_front_count`` (face down) or above ``fallen_back_count`` (face up)."""

    board_id: int
    centre_count: int
    max_count: int
    gyro: tuple[ImuChannel, ImuChannel, ImuChannel]
    accel: tuple[ImuChannel, ImuChannel, ImuChannel]
    accel_scale_other: float
    fallen_front_count: int
    fallen_back_count: int
    fallen_window: int


@dataclass(frozen=True)
class Spec:
    """The whole validated OP2 spec."""

    name: str
    root_link: str
    servo: Servo
    foot: Foot
    points: Mapping[str, PointSpec]
    joints: tuple[Joint, ...]
    lumped_masses: tuple[LumpedMass, ...]
    inertials: tuple[Inertial, ...]
    collisions: tuple[Collision, ...]
    geometry: Geometry
    path: str
    sha256: str
    sources: Mapping[str, str] = field(default_factory=dict)
    imu: ImuSpec | None = None
    framework_leg_m: tuple[float, float, float] | None = None   # the firmware's own thigh, calf, ankle-to-sole [m]

    @functools.cached_property
    def joint_names(self) -> tuple[str, ...]:
        """Official joint names in Dynamixel ID order (worked out once: per-tick code reads them every 8 ms)."""
        return tuple(j.name for j in self.joints)

    def joint(self, name: str) -> Joint:
        """The joint called ``name`` (official ROS/URDF name)."""
        for j in self.joints:
            if j.name == name:
                return j
        raise SpecError(f"{self.path}: no joint named {name!r}")

    def inertial(self, link: str) -> Inertial:
        """The inertial of ``link``."""
        for item in self.inertials:
            if item.link == link:
                return item
        raise SpecError(f"{self.path}: no inertial for link {link!r}")

    def foot_box(self, side: Side) -> Collision:
        """The collision box of the ``left`` or ``right`` foot: the real sole is its underside."""
        link = self.joint(f"{side[0]}_ank_roll").child
        boxes = self.collisions_of(link, "box")
        if not boxes or any(abs(a) > 1e-12 for a in boxes[0].origin_rpy):
            raise SpecError(f"expected an unrotated box collision shape on {link} (the sole)", self.path)
        return boxes[0]

    def sole_extents(self, side: Side, br: float = 1.0) -> tuple[float, float, float, float]:
        """(front, back, left, right) half-extents [m] of the real sole (the foot box's underside) about the sole
        centre below the ankle, shrunk by ``br``."""
        box = self.foot_box(side)
        (sx, sy, _), (ox, oy, _) = box.size, box.origin_xyz
        return br * (ox + sx / 2), br * (sx / 2 - ox), br * (oy + sy / 2), br * (sy / 2 - oy)

    def collisions_of(self, link: str, shape: str | None = None) -> tuple[Collision, ...]:
        """The collision shapes fixed to ``link`` (of one ``shape`` kind if given)."""
        return tuple(c for c in self.collisions if c.link == link and (shape is None or c.shape == shape))

    @property
    def lumped_total_mass(self) -> float:
        """Sum of the lumped link masses [kg]."""
        return sum(m.mass for m in self.lumped_masses)
