"""Load and validate the OP2 spec (``specs/op2.toml``) into frozen dataclasses.

The spec is the single source of every robot number. :func:`load_spec` rejects a bad file (missing or unknown key,
wrong type, non-positive length, lower >= upper limit, a book variable mapped twice) with a :class:`SpecError`
that names the file and the key. :class:`Geometry` holds the lengths the kinematic models use, derived from the
official joint table so that no length is written twice.
"""

from __future__ import annotations

import functools
import hashlib
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Mapping

from .errors import SpecError
from .tablereader import TableReader

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

SCHEMA = "op2motion.spec/1"
SUPPORTS = ("left", "right")
POSE_SUPPORTS = ("left", "right", "double")


def swing_of(support: str) -> str:
    """The swing side of a single-support pose (``left`` -> ``right`` and back)."""
    return "right" if support == "left" else "left"


def stance_of(support: str) -> str:
    """The foot the world frame is rooted on: the support foot, the left one for ``double`` support."""
    return "right" if support == "right" else "left"


def feet_of(support: str) -> tuple[str, ...]:
    """The feet that carry the robot: both for ``double`` support."""
    return SUPPORTS if support == "double" else (stance_of(support),)
BOOK_VARS = tuple([f"th{i}" for i in range(1, 12)] + [f"phi{i}" for i in range(1, 7)] + [f"psi{i}" for i in range(1, 4)])


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
    lower: float
    upper: float
    book: Mapping[str, BookMap]


@dataclass(frozen=True)
class Servo:
    """Dynamixel MX-28 facts."""

    model: str
    ticks_per_rev: int
    center_tick: int
    min_tick: int
    max_tick: int
    framework_deg_per_tick: float
    stall_torque_nm: float
    no_load_speed_rad_s: float
    invalid_bit: int
    torque_off_bit: int

    @property
    def rad_per_tick(self) -> float:
        """Exact angle of one tick [rad]."""
        return 2.0 * math.pi / self.ticks_per_rev


@dataclass(frozen=True)
class Foot:
    """Foot rectangle about the sole centre (below the ankle) [m], for the left foot; mirrored on the right."""

    sole_below_ankle: float
    front: float
    back: float
    inner: float
    outer: float

    def extents(self, side: str, br: float = 1.0) -> tuple[float, float, float, float]:
        """(front, back, left, right) half-extents [m] of the ``side`` sole about its centre, shrunk by ``br``.

        The outer edge is on the left of the left foot and on the right of the right foot (book fig. 2.30).
        """
        left, right = (self.outer, self.inner) if side == "left" else (self.inner, self.outer)
        return br * self.front, br * self.back, br * left, br * right

    def corners(self, side: str) -> tuple[tuple[float, float], ...]:
        """Sole corners (forward, left) [m] about the sole centre: front-left, front-right, back-right, back-left."""
        front, back, left, right = self.extents(side)
        return ((front, left), (front, -right), (-back, -right), (-back, left))


@dataclass(frozen=True)
class PointSpec:
    """A named point fixed to a link: ``xyz`` [m] in the frame of ``link``."""

    link: str
    xyz: tuple[float, float, float]


@dataclass(frozen=True)
class LumpedMass:
    """A lumped mass [kg] at ``fraction`` of the way from body point ``start`` to body point ``end``."""

    name: str
    mass: float
    start: str
    end: str
    fraction: float


@dataclass(frozen=True)
class Inertial:
    """A per-link inertial (Webots data): CoM [m] and tensor about the CoM [kg·m²] in the Webots link frame."""

    link: str
    webots: str
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]
    webots_frame_xyz: tuple[float, float, float]
    webots_frame_rpy: tuple[float, float, float]


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

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Official joint names in Dynamixel ID order."""
        return tuple(j.name for j in self.joints)

    def joint(self, name: str) -> Joint:
        """The joint called ``name`` (official ROS/URDF name)."""
        for j in self.joints:
            if j.name == name:
                return j
        raise SpecError(f"{self.path}: no joint named {name!r}")

    def collisions_of(self, link: str, shape: str | None = None) -> tuple[Collision, ...]:
        """The collision shapes fixed to ``link`` (of one ``shape`` kind if given)."""
        return tuple(c for c in self.collisions if c.link == link and (shape is None or c.shape == shape))

    @property
    def lumped_total_mass(self) -> float:
        """Sum of the lumped link masses [kg]."""
        return sum(m.mass for m in self.lumped_masses)


def _servo(r: TableReader) -> Servo:
    s = Servo(r.get("model", str), r.get("ticks_per_rev", int), r.get("center_tick", int), r.get("min_tick", int),
              r.get("max_tick", int), r.number("framework_deg_per_tick", positive=True),
              r.number("stall_torque_nm", positive=True), r.number("no_load_speed_rad_s", positive=True),
              r.get("invalid_bit", int), r.get("torque_off_bit", int))
    r.done()
    if not (s.min_tick < s.center_tick < s.max_tick < s.ticks_per_rev):
        raise SpecError(f"{r.path}: servo: expected min_tick < center_tick < max_tick < ticks_per_rev")
    return s


def _foot(r: TableReader) -> Foot:
    f = Foot(r.number("sole_below_ankle_m", positive=True), r.number("front_m", positive=True),
             r.number("back_m", positive=True), r.number("inner_m", positive=True), r.number("outer_m", positive=True))
    r.done()
    return f


def _joint(r: TableReader) -> Joint:
    name = r.get("name", str)
    lower, upper = r.vector("limit_deg", 2)
    if not lower < upper:
        raise SpecError(f"{r.path}: {r.where}.limit_deg ({name}): expected lower < upper, got [{lower}, {upper}]")
    axis = r.vector("axis")
    if abs(math.sqrt(sum(a * a for a in axis)) - 1.0) > 1e-9:
        raise SpecError(f"{r.path}: {r.where}.axis ({name}): expected a unit vector, got {list(axis)}")
    books = r.sub("book")
    book: dict[str, BookMap] = {}
    for support in SUPPORTS:
        b = books.sub(support)
        var, sign = b.get("var", str), b.get("sign", int)
        if var not in BOOK_VARS:
            raise SpecError(f"{r.path}: {b.where}.var: expected one of th1..th11, phi1..phi6, psi1..psi3, got {var!r}")
        if sign not in (-1, 1):
            raise SpecError(f"{r.path}: {b.where}.sign: expected 1 or -1, got {sign!r}")
        book[support] = BookMap(var, sign, math.radians(b.number("offset_deg")))
        b.done()
    books.done()
    joint = Joint(name, r.get("id", int), r.get("framework", str), r.get("webots", str), r.get("parent", str),
                  r.get("child", str), r.vector("origin_xyz_m"),  # type: ignore[arg-type]
                  tuple(math.radians(v) for v in r.vector("origin_rpy_deg")), axis,  # type: ignore[arg-type]
                  math.radians(lower), math.radians(upper), book)
    r.done()
    return joint


def _check_joints(path: str, joints: list[Joint]) -> None:
    names = [j.name for j in joints]
    if len(set(names)) != len(names):
        raise SpecError(f"{path}: joint: duplicate joint names")
    ids = sorted(j.id for j in joints)
    if ids != list(range(1, len(joints) + 1)):
        raise SpecError(f"{path}: joint.id: expected the Dynamixel IDs 1..{len(joints)} once each, got {ids}")
    for support in SUPPORTS:
        used = sorted(j.book[support].var for j in joints)
        if used != sorted(BOOK_VARS):
            raise SpecError(f"{path}: joint.book.{support}: expected each book variable exactly once, got {used}")


def _geometry(path: str, joints: Mapping[str, Joint], points: Mapping[str, PointSpec], foot: Foot) -> Geometry:
    """Derive the model lengths from the official joint table, checking the structure the models assume."""

    def origin(name: str) -> tuple[float, float, float]:
        if name not in joints:
            raise SpecError(f"{path}: joint {name!r} is required by the kinematic models")
        return joints[name].origin_xyz

    def need(cond: bool, what: str) -> None:
        if not cond:
            raise SpecError(f"{path}: joint table: {what} (the kinematic models assume it)")

    for name, joint in joints.items():
        if name.startswith("l_") and "r_" + name[2:] in joints:
            mirror = joints["r_" + name[2:]]
            (x, y, z), (rr, pp, yy) = joint.origin_xyz, joint.origin_rpy
            need(mirror.origin_xyz == (x, -y, z) and mirror.origin_rpy == (-rr, pp, -yy),
                 f"{mirror.name} origin must mirror {name}'s (x, -y, z; -roll, pitch, -yaw)")
    for side, sgn in (("l", 1.0), ("r", -1.0)):
        for joint in ("hip_pitch", "ank_roll"):
            need(origin(f"{side}_{joint}") == (0.0, 0.0, 0.0), f"{side}_{joint} origin must be at its parent's origin")
        hx, hy, hz = origin(f"{side}_hip_yaw")
        need(abs(hy - sgn * origin("l_hip_yaw")[1]) < 1e-12, "hip yaw origins must be left/right symmetric")
        for joint in ("hip_roll", "knee", "ank_pitch"):
            ox, oy, _ = origin(f"{side}_{joint}")
            need(ox == 0.0 and oy == 0.0, f"{side}_{joint} origin must lie straight below its parent")
        sx, sy, sz = origin(f"{side}_sho_pitch")
        need(sx == 0.0 and sz == 0.0 and abs(sy - sgn * origin("l_sho_pitch")[1]) < 1e-12,
             "shoulder pitch origins must lie on the torso's y axis, symmetric")
    hx, hy, hz = origin("l_hip_yaw")
    rx, ry, rz = origin("l_sho_roll")
    ex, ey, ez = origin("l_el")
    pan, tilt = origin("head_pan"), origin("head_tilt")
    need(ey == 0.0 and rx == 0.0, "shoulder roll and elbow offsets must lie in the arm's plane")
    need(pan[:2] == (0.0, 0.0) and tilt[:2] == (0.0, 0.0), "head joints must lie on the torso's z axis")
    hand = points["left_hand"].xyz
    need(hand[0] == 0.0 and hand[1] == 0.0 and hand[2] < 0, "the hand must lie on the forearm axis (-z of l_el_link)")
    lengths = dict(
        ankle_to_sole=foot.sole_below_ankle, calf=-origin("l_ank_pitch")[2], thigh=-origin("l_knee")[2],
        hip_yaw_to_roll=-origin("l_hip_roll")[2], hip_half_width=hy, hip_x=hx, torso=-hz,
        shoulder_half_width=origin("l_sho_pitch")[1], shoulder_roll_lateral=ry, shoulder_roll_drop=-rz,
        elbow_forward=ex, upper_arm=-ez, lower_arm=-hand[2], head_pan_height=pan[2],
        head_tilt_height=pan[2] + tilt[2], head_length=math.dist((0.0, 0.0, 0.0), points["head_top"].xyz))
    for key, value in lengths.items():
        if key not in ("hip_x", "elbow_forward", "shoulder_roll_lateral", "shoulder_roll_drop") and value <= 0:
            raise SpecError(f"{path}: derived length {key} = {value} m must be positive")
    return Geometry(**lengths)


def parse_spec(text: str, path: str = "<spec>") -> Spec:
    """Validate TOML text into a :class:`Spec`; ``path`` names the file in error messages."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{path}: not valid TOML: {exc}") from None
    top = TableReader(path, "", raw)
    if top.get("schema", str) != SCHEMA:
        raise SpecError(f"{path}: schema: expected {SCHEMA!r}, got {raw['schema']!r}")
    name, root = top.get("name", str), top.get("root_link", str)
    servo, foot = _servo(top.sub("servo")), _foot(top.sub("foot"))
    points_reader = top.sub("points")
    points: dict[str, PointSpec] = {}
    for key in list(points_reader.table):
        pr = points_reader.sub(key)
        points[key] = PointSpec(pr.get("link", str), pr.vector("xyz_m"))  # type: ignore[arg-type]
        pr.done()
    points_reader.done()
    for required in ("left_hand", "right_hand", "head_top"):
        if required not in points:
            raise SpecError(f"{path}: missing key 'points.{required}'")
    joints = [_joint(r) for r in top.array("joint")]
    _check_joints(path, joints)
    joints.sort(key=lambda j: j.id)
    masses = []
    for r in top.array("lumped_mass"):
        fraction = r.number("fraction")
        if not 0.0 <= fraction <= 1.0:
            raise SpecError(f"{path}: {r.where}.fraction: expected 0..1, got {fraction}")
        masses.append(LumpedMass(r.get("name", str), r.number("mass_kg", positive=True), r.get("from", str),
                                 r.get("to", str), fraction))
        r.done()
    inertials = []
    for r in top.array("inertial"):
        inertials.append(Inertial(r.get("link", str), r.get("webots", str), r.number("mass_kg", positive=True),
                                  r.vector("com_m"), r.vector("inertia", 6),  # type: ignore[arg-type]
                                  r.vector("webots_frame_xyz_m"),  # type: ignore[arg-type]
                                  tuple(math.radians(v) for v in r.vector("webots_frame_rpy_deg"))))  # type: ignore[arg-type]
        r.done()
    collisions = []
    for r in top.array("collision"):
        shape = r.get("shape", str)
        if shape not in COLLISION_SIZES:
            raise SpecError(f"{path}: {r.where}.shape: expected box, cylinder or sphere, got {shape!r}")
        size = r.vector("size_m", COLLISION_SIZES[shape])
        if min(size) <= 0:
            raise SpecError(f"{path}: {r.where}.size_m: expected positive sizes, got {list(size)}")
        collisions.append(Collision(r.get("link", str), shape, size, r.vector("origin_xyz_m"),  # type: ignore[arg-type]
                                    tuple(math.radians(v) for v in r.vector("origin_rpy_deg"))))  # type: ignore[arg-type]
        r.done()
    top.done()
    links = {root} | {j.child for j in joints}
    for item, kind in [(i, "inertial") for i in inertials] + [(c, "collision") for c in collisions]:
        if item.link not in links:
            raise SpecError(f"{path}: {kind} link {item.link!r}: expected one of the joint tree's links")
    by_name = {j.name: j for j in joints}
    geometry = _geometry(path, by_name, points, foot)
    return Spec(name, root, servo, foot, points, tuple(joints), tuple(masses), tuple(inertials), tuple(collisions),
                geometry, path, hashlib.sha256(text.encode("utf-8")).hexdigest())


def load_spec(path: str | Path | None = None) -> Spec:
    """Load a spec file; ``None`` loads the OP2 spec shipped with op2motion (cached)."""
    if path is None:
        return default_spec()
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise SpecError(f"{p}: cannot read spec: {exc.strerror}") from None
    return parse_spec(text, str(p))


def _shipped_spec_text() -> str:
    """``specs/op2.toml``: installed as package data ``op2motion.specs``, or beside the package in a source tree."""
    source_tree = Path(__file__).resolve().parents[1] / "specs" / "op2.toml"
    if source_tree.is_file():
        return source_tree.read_text(encoding="utf-8")
    try:
        return resources.files("op2motion.specs").joinpath("op2.toml").read_text(encoding="utf-8")
    except (ModuleNotFoundError, OSError) as exc:
        raise SpecError(f"specs/op2.toml: the shipped spec is missing from this installation ({exc})") from None


@functools.lru_cache(maxsize=1)
def default_spec() -> Spec:
    """The shipped OP2 spec (``specs/op2.toml``), loaded once."""
    return parse_spec(_shipped_spec_text(), "specs/op2.toml")
