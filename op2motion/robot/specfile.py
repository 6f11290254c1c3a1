"""Read and check a spec file (``specs/op2.toml``) into a :class:`op2motion.robot.spec.Spec`.

Everything that is not a sound description of a robot is a :class:`SpecError` naming the file and the key, before
any model is built from it: a file that is not UTF-8 TOML, a missing or unknown key, a wrong type, a number that is
not finite; a non-positive length, mass or size; an inertia tensor that is not positive definite or breaks the
triangle inequality of its principal moments; a joint range whose lower end is not below its upper end, a
cable-safe range outside the mechanical one, a mechanical range beyond the servo's; a link, joint or body point
that is referenced but does not exist, a joint tree that is not a tree; a book variable mapped twice; left/right
asymmetry where the kinematic models assume symmetry.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import math
import sys
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Mapping

import numpy as np

from op2motion.errors import SpecError
from op2motion.fileio import read_text
from op2motion.robot.spec import (
    BOOK_VARS,
    COLLISION_SIZES,
    GRAVITY_M_S2,
    SCHEMA,
    BookMap,
    Collision,
    Foot,
    Geometry,
    ImuChannel,
    ImuSpec,
    Inertial,
    Joint,
    LumpedMass,
    PointSpec,
    Rating,
    Servo,
    Spec,
    Uncertainty,
    inertia_matrix,
    rpy_matrix,
)
from op2motion.robot.support import SIDES
from op2motion.robot.tablereader import TableReader

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

#: Body points the kinematic models make besides the joints and the spec's named points.
DERIVED_POINTS = ("pelvis", "neck", "left_sole", "right_sole")
INERTIA_REL_TOL = 1e-9   # relative slack of the positive-definite and triangle-inequality checks


def _servo(r: TableReader) -> Servo:
    ratings = []
    for rr in r.array("rating"):
        ratings.append(Rating(rr.number("voltage_v", positive=True), rr.number("stall_torque_nm", positive=True),
                              rr.number("no_load_speed_rad_s", positive=True)))
        rr.done()
    s = Servo(r.get("model", str), r.get("ticks_per_rev", int), r.get("center_tick", int), r.get("min_tick", int),
              r.get("max_tick", int), r.number("framework_deg_per_tick", positive=True), r.get("invalid_bit", int),
              r.get("torque_off_bit", int), tuple(ratings), r.number("supply_voltage_v", positive=True),
              r.get("p_gain_default", int), r.number("duty_per_p_rad", positive=True),
              r.number("max_duty", positive=True), r.number("armature_kg_m2", nonnegative=True),
              r.number("friction_nm", nonnegative=True), r.number("viscous_nm_s_rad", nonnegative=True),
              r.number("backlash_rad", nonnegative=True))
    if "operating_voltage_v" in r.table:
        low, high = r.vector("operating_voltage_v", 2)
        if not 0.0 < low < high:
            raise SpecError(f"expected 0 < lowest < highest, got [{low}, {high}]",
                            f"{r.path}: servo.operating_voltage_v")
        s = replace(s, operating_voltage_v=(low, high))
    r.done()
    if not (0 <= s.min_tick < s.center_tick < s.max_tick < s.ticks_per_rev):
        raise SpecError("expected 0 <= min_tick < center_tick < max_tick < ticks_per_rev", f"{r.path}: servo")
    if not s.ratings or s.supply_voltage_v not in [x.voltage_v for x in s.ratings]:
        raise SpecError(f"expected one of the rated voltages {[x.voltage_v for x in s.ratings]}, got "
                        f"{s.supply_voltage_v}", f"{r.path}: servo.supply_voltage_v")
    if not 1 <= s.p_gain_default <= 254:
        raise SpecError(f"expected an MX-28 P gain 1..254, got {s.p_gain_default}", f"{r.path}: servo.p_gain_default")
    if s.max_duty > 1.0:
        raise SpecError(f"expected a duty cycle in (0, 1], got {s.max_duty}", f"{r.path}: servo.max_duty")
    return s


def _foot(r: TableReader) -> Foot:
    f = Foot(r.number("sole_below_ankle_m", positive=True), r.number("front_m", positive=True),
             r.number("back_m", positive=True), r.number("inner_m", positive=True), r.number("outer_m", positive=True))
    r.done()
    return f


def _range(r: TableReader, key: str, name: str) -> tuple[float, float]:
    lower, upper = r.vector(key, 2)
    if not lower < upper:
        raise SpecError(f"({name}): expected lower < upper, got [{lower}, {upper}]", f"{r.path}: {r.where}.{key}")
    return math.radians(lower), math.radians(upper)


def _webots_range(r: TableReader, name: str) -> tuple[float, float]:
    lower, upper = r.vector("webots_range_rad", 2)
    if not lower < upper:
        raise SpecError(f"({name}): expected lower < upper, got [{lower}, {upper}]",
                        f"{r.path}: {r.where}.webots_range_rad")
    return float(lower), float(upper)


def _within_ticks(joint: Joint, servo: Servo) -> Joint:
    """The joint's ranges within what the servo can be told: ticks ``min_tick``..``max_tick`` (-180° to +179.91° on
    the MX-28). +180° would be tick 4096, which does not exist: one rule for every reader (pose files, ``fk``,
    ``convert``, ``export``, the studio), so a range written as ±180° ends at the last tick."""
    lo, hi = (servo.min_tick - servo.center_tick) * servo.rad_per_tick, (servo.max_tick - servo.center_tick) * \
        servo.rad_per_tick

    def clip(r: tuple[float, float]) -> tuple[float, float]:
        return max(r[0], lo), min(r[1], hi)

    return dataclasses.replace(joint, mechanical=clip(joint.mechanical), safe=clip(joint.safe))


def _joint(r: TableReader) -> Joint:
    name = r.get("name", str)
    safe, mech = _range(r, "cable_safe_deg", name), _range(r, "mechanical_deg", name)
    if not (mech[0] <= safe[0] and safe[1] <= mech[1]):
        raise SpecError(f"({name}): expected the cable-safe range inside the mechanical range",
                        f"{r.path}: {r.where}.cable_safe_deg")
    if max(abs(mech[0]), abs(mech[1])) > math.pi + 1e-12:
        raise SpecError(f"({name}): expected a range within the servo's ±180°", f"{r.path}: {r.where}.mechanical_deg")
    axis = r.vector("axis")
    if abs(math.sqrt(sum(a * a for a in axis)) - 1.0) > 1e-9:
        raise SpecError(f"({name}): expected a unit vector, got {list(axis)}", f"{r.path}: {r.where}.axis")
    books = r.sub("book")
    book: dict[str, BookMap] = {}
    for support in SIDES:
        b = books.sub(support)
        var, sign = b.get("var", str), b.get("sign", int)
        if var not in BOOK_VARS:
            raise SpecError(f"expected one of th1..th11, phi1..phi6, psi1..psi3, got {var!r}",
                            f"{r.path}: {b.where}.var")
        if sign not in (-1, 1):
            raise SpecError(f"expected 1 or -1, got {sign!r}", f"{r.path}: {b.where}.sign")
        book[support] = BookMap(var, sign, math.radians(b.number("offset_deg")))
        b.done()
    books.done()
    joint = Joint(name, r.get("id", int), r.get("framework", str), r.get("webots", str), r.get("parent", str),
                  r.get("child", str), r.vector("origin_xyz_m"),  # type: ignore[arg-type]
                  tuple(math.radians(v) for v in r.vector("origin_rpy_deg")), axis,  # type: ignore[arg-type]
                  safe, mech, book, _webots_range(r, name))
    r.done()
    return joint


def _check_joints(path: str, root: str, joints: list[Joint]) -> None:
    """IDs 1..N once, unique names, a tree of links rooted at ``root``, each book variable mapped once."""
    names = [j.name for j in joints]
    if len(set(names)) != len(names):
        raise SpecError("duplicate joint names", f"{path}: joint")
    ids = sorted(j.id for j in joints)
    if ids != list(range(1, len(joints) + 1)):
        raise SpecError(f"expected the Dynamixel IDs 1..{len(joints)} once each, got {ids}", f"{path}: joint.id")
    children = [j.child for j in joints]
    if len(set(children)) != len(children) or root in children:
        raise SpecError("expected every child link once, and never the root link", f"{path}: joint.child")
    parent_of = {j.child: j.parent for j in joints}
    for j in joints:
        if j.parent != root and j.parent not in parent_of:
            raise SpecError(f"({j.name}): parent link {j.parent!r} does not exist", f"{path}: joint.parent")
        link, seen = j.child, set()
        while link != root:            # every chain ends at the root: no loops
            if link in seen:
                raise SpecError(f"({j.name}): the links form a loop", f"{path}: joint.parent")
            seen.add(link)
            link = parent_of[link]
    for support in SIDES:
        used = sorted(j.book[support].var for j in joints)
        if used != sorted(BOOK_VARS):
            raise SpecError(f"expected each book variable exactly once, got {used}", f"{path}: joint.book.{support}")


def _check_inertia(path: str, where: str, inertia: tuple[float, ...]) -> None:
    """Symmetric positive definite with principal moments that satisfy the triangle inequality."""
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    moments = np.linalg.eigvalsh(np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
    scale = max(float(np.max(np.abs(moments))), 1e-300)
    if moments[0] <= INERTIA_REL_TOL * scale:
        raise SpecError(f"expected a positive definite inertia tensor, got principal moments {moments.tolist()}",
                        f"{path}: {where}.inertia")
    if moments[2] > moments[0] + moments[1] + INERTIA_REL_TOL * scale:
        raise SpecError(f"principal moments {moments.tolist()} break the triangle inequality (no rigid body has them)",
                        f"{path}: {where}.inertia")


def _geometry(path: str, joints: Mapping[str, Joint], points: Mapping[str, PointSpec], foot: Foot) -> Geometry:
    """Derive the model lengths from the official joint table, checking the structure the models assume."""

    def origin(name: str) -> tuple[float, float, float]:
        if name not in joints:
            raise SpecError(f"joint {name!r} is required by the kinematic models", path)
        return joints[name].origin_xyz

    def need(cond: bool, what: str) -> None:
        if not cond:
            raise SpecError(f"joint table: {what} (the kinematic models assume it)", path)

    for name, joint in joints.items():
        if name.startswith("l_") and "r_" + name[2:] in joints:
            mirror = joints["r_" + name[2:]]
            (x, y, z), (rr, pp, yy) = joint.origin_xyz, joint.origin_rpy
            need(mirror.origin_xyz == (x, -y, z) and mirror.origin_rpy == (-rr, pp, -yy),
                 f"{mirror.name} origin must mirror {name}'s (x, -y, z; -roll, pitch, -yaw)")
    for side, sgn in (("l", 1.0), ("r", -1.0)):
        for part in ("hip_pitch", "ank_roll"):
            need(origin(f"{side}_{part}") == (0.0, 0.0, 0.0), f"{side}_{part} origin must be at its parent's origin")
        hx, hy, hz = origin(f"{side}_hip_yaw")
        need(abs(hy - sgn * origin("l_hip_yaw")[1]) < 1e-12, "hip yaw origins must be left/right symmetric")
        for part in ("hip_roll", "knee", "ank_pitch"):
            ox, oy, _ = origin(f"{side}_{part}")
            need(ox == 0.0 and oy == 0.0, f"{side}_{part} origin must lie straight below its parent")
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
            raise SpecError(f"derived length {key} = {value} m must be positive", path)
    return Geometry(**lengths)


def _sources(top: TableReader) -> dict[str, str]:
    """The ``[sources]`` table: short key -> citation (optional)."""
    if "sources" not in top.table:
        return {}
    reader = top.sub("sources")
    out = {key: reader.get(key, str) for key in list(reader.table)}
    reader.done()
    return out


def _uncertainty(r: TableReader) -> Uncertainty | None:
    """A link's stated uncertainty (``mass_uncertainty`` and ``com_uncertainty_m`` together, or neither)."""
    given = [key for key in ("mass_uncertainty", "com_uncertainty_m") if key in r.table]
    if not given:
        return None
    if len(given) == 1:
        raise SpecError(f"{r.path}: {r.where}: expected mass_uncertainty and com_uncertainty_m together, got only "
                        f"{given[0]}")
    fraction = r.number("mass_uncertainty", nonnegative=True)
    if fraction >= 1.0:
        raise SpecError(f"{r.path}: {r.where}.mass_uncertainty: expected a fraction below 1, got {fraction!r}")
    rows = r.get("com_uncertainty_m", list)
    bounds = []
    for row in rows if len(rows) == 3 else ():
        ok = isinstance(row, list) and len(row) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in row)
        if not ok or not row[0] <= 0.0 <= row[1]:
            break
        bounds.append((float(row[0]), float(row[1])))
    if len(bounds) != 3:
        raise SpecError(f"{r.path}: {r.where}.com_uncertainty_m: expected [[low, high], [low, high], [low, high]] "
                        f"[m] with low <= 0 <= high per axis, got {rows!r}")
    return Uncertainty(fraction, (bounds[0], bounds[1], bounds[2]))


def _inertial(r: TableReader, sources: Mapping[str, str]) -> Inertial:
    """One ``[[inertial]]``: in the link frame, or (older files) in a Webots frame placed by
    ``webots_frame_xyz_m`` / ``webots_frame_rpy_deg``, re-expressed here in the link frame."""
    inertia = r.vector("inertia", 6)
    _check_inertia(r.path, r.where, inertia)
    com = np.asarray(r.vector("com_m"))
    tensor = inertia_matrix(inertia)
    if "webots_frame_xyz_m" in r.table or "webots_frame_rpy_deg" in r.table or "webots" in r.table:
        r.get("webots", str)
        rot = rpy_matrix(tuple(math.radians(v) for v in r.vector("webots_frame_rpy_deg")))  # type: ignore[arg-type]
        com = rot @ com + np.asarray(r.vector("webots_frame_xyz_m"))
        tensor = rot @ tensor @ rot.T
    cited: dict[str, str] = {}
    if "sources" in r.table:
        s = r.sub("sources")
        for figure in ("mass", "com", "inertia"):
            key = s.get(figure, str)
            if key not in sources:
                raise SpecError(f"{r.path}: {r.where}.sources.{figure}: expected a key of [sources] "
                                f"({', '.join(sorted(sources)) or 'none given'}), got {key!r}")
            cited[figure] = key
        s.done()
    item = Inertial(r.get("link", str), r.number("mass_kg", positive=True),
                    (float(com[0]), float(com[1]), float(com[2])),
                    (float(tensor[0, 0]), float(tensor[1, 1]), float(tensor[2, 2]), float(tensor[0, 1]),
                     float(tensor[0, 2]), float(tensor[1, 2])), cited, _uncertainty(r))
    r.done()
    return item


def _masses(top: TableReader, sources: Mapping[str, str]) -> tuple[list[LumpedMass], list[Inertial], list[Collision]]:
    masses = []
    for r in top.array("lumped_mass"):
        fraction = r.number("fraction")
        if not 0.0 <= fraction <= 1.0:
            raise SpecError(f"expected 0..1, got {fraction}", f"{r.path}: {r.where}.fraction")
        masses.append(LumpedMass(r.get("name", str), r.number("mass_kg", positive=True), r.get("from", str),
                                 r.get("to", str), fraction))
        r.done()
    inertials = [_inertial(r, sources) for r in top.array("inertial")]
    collisions = []
    for r in top.array("collision"):
        shape = r.get("shape", str)
        if shape not in COLLISION_SIZES:
            raise SpecError(f"expected box, cylinder or sphere, got {shape!r}", f"{r.path}: {r.where}.shape")
        size = r.vector("size_m", COLLISION_SIZES[shape])
        if min(size) <= 0:
            raise SpecError(f"expected positive sizes, got {list(size)}", f"{r.path}: {r.where}.size_m")
        collisions.append(Collision(r.get("link", str), shape, size, r.vector("origin_xyz_m"),  # type: ignore[arg-type]
                                    tuple(math.radians(v) for v in r.vector("origin_rpy_deg"))))  # type: ignore[arg-type]
        r.done()
    return masses, inertials, collisions


IMU_SENSORS = {"gyro": ("scale_deg_s", math.radians(1.0)), "accel": ("scale_g", GRAVITY_M_S2)}
AXES = ("x", "y", "z")


def _imu_channel(r: TableReader) -> ImuChannel:
    sensor = r.get("sensor", str)
    if sensor not in IMU_SENSORS:
        raise SpecError(f"{r.path}: {r.where}.sensor: expected gyro or accel, got {sensor!r}")
    axis, sign, register = r.get("axis", str), r.get("sign", int), r.get("register", int)
    if axis not in AXES:
        raise SpecError(f"{r.path}: {r.where}.axis: expected x, y or z, got {axis!r}")
    if sign not in (-1, 1):
        raise SpecError(f"{r.path}: {r.where}.sign: expected 1 or -1, got {sign!r}")
    if not 0 <= register <= 254:
        raise SpecError(f"{r.path}: {r.where}.register: expected a register address 0..254, got {register!r}")
    key, si = IMU_SENSORS[sensor]
    channel = ImuChannel(sensor, register, AXES.index(axis), sign, r.number(key, positive=True) * si,
                         r.get("source", str), r.get("reasoning", str))
    r.done()
    return channel


def _framework_leg(r: TableReader) -> tuple[float, float, float]:
    """The ``[framework]`` table: the leg lengths the ROBOTIS firmware's own kinematics uses [m]."""
    leg = (r.number("thigh_m", positive=True), r.number("calf_m", positive=True),
           r.number("ankle_m", positive=True))
    r.done()
    return leg


def _imu(r: TableReader) -> ImuSpec:
    """The ``[imu]`` table: one gyro and one accelerometer channel per torso axis, registers all different."""
    channels = [_imu_channel(c) for c in r.array("channel")]
    by_sensor: dict[str, list[ImuChannel]] = {}
    for sensor in IMU_SENSORS:
        mine = sorted((c for c in channels if c.sensor == sensor), key=lambda c: c.axis)
        if [c.axis for c in mine] != [0, 1, 2]:
            raise SpecError(f"{r.path}: imu.channel: expected one {sensor} channel per axis x, y, z, got "
                            f"{[AXES[c.axis] for c in mine]}")
        by_sensor[sensor] = mine
    registers = [c.register for c in channels]
    if len(set(registers)) != len(registers):
        raise SpecError(f"{r.path}: imu.channel: expected each register once, got {registers}")
    centre, top = r.get("centre_count", int), r.get("max_count", int)
    front, back = r.get("fallen_front_count", int), r.get("fallen_back_count", int)
    if not 0 < front < centre < back < top:
        raise SpecError(f"{r.path}: imu: expected 0 < fallen_front_count < centre_count < fallen_back_count < "
                        f"max_count, got {front}, {centre}, {back}, {top}")
    g, a = by_sensor["gyro"], by_sensor["accel"]
    imu = ImuSpec(r.get("board_id", int), centre, top, (g[0], g[1], g[2]), (a[0], a[1], a[2]),
                  r.number("accel_scale_other_g", positive=True) * GRAVITY_M_S2, front, back,
                  r.get("fallen_window", int))
    if imu.fallen_window < 1:
        raise SpecError(f"{r.path}: imu.fallen_window: expected at least 1 sample, got {imu.fallen_window}")
    r.done()
    return imu


def parse_spec(text: str, path: str = "<spec>") -> Spec:
    """Check TOML text and return its :class:`Spec`; ``path`` names the file in error messages."""
    try:
        encoded = text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise SpecError(f"not valid Unicode text (a lone surrogate at character {exc.start})", path) from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"not valid TOML: {exc}", path) from None
    top = TableReader(path, "", raw)
    # (the URDF root "base_link" and the sole frames are made by the URDF generator)
    if top.get("schema", str) != SCHEMA:
        raise SpecError(f"expected {SCHEMA!r}, got {raw['schema']!r}", f"{path}: schema")
    name, root = top.get("name", str), top.get("root_link", str)
    servo, foot = _servo(top.sub("servo")), _foot(top.sub("foot"))
    points_reader = top.sub("points")
    points: dict[str, PointSpec] = {}
    for key in list(points_reader.table):
        pr = points_reader.sub(key)
        points[key] = PointSpec(pr.get("link", str), pr.vector("xyz_m"), pr.get("frame", str))  # type: ignore[arg-type]
        pr.done()
    points_reader.done()
    for required in ("left_hand", "right_hand", "head_top"):
        if required not in points:
            raise SpecError(f"missing key 'points.{required}'", path)
    joints = [_within_ticks(_joint(r), servo) for r in top.array("joint")]
    _check_joints(path, root, joints)
    joints.sort(key=lambda j: j.id)
    sources = _sources(top)
    masses, inertials, collisions = _masses(top, sources)
    imu = _imu(top.sub("imu")) if "imu" in top.table else None
    framework_leg = _framework_leg(top.sub("framework")) if "framework" in top.table else None
    top.done()
    links = {root} | {j.child for j in joints}
    named = [(p.link, f"points.{k}") for k, p in points.items()] + [(i.link, "inertial") for i in inertials] + \
            [(c.link, "collision") for c in collisions]
    for link, where in named:
        if link not in links:
            raise SpecError(f"link {link!r} does not exist (expected one of the joint tree's links)",
                            f"{path}: {where}")
    body_points = set(DERIVED_POINTS) | set(points) | {j.name for j in joints}
    for m in masses:
        for end in (m.start, m.end):
            if end not in body_points:
                raise SpecError(f"({m.name}): body point {end!r} does not exist", f"{path}: lumped_mass")
    geometry = _geometry(path, {j.name: j for j in joints}, points, foot)
    return Spec(name, root, servo, foot, points, tuple(joints), tuple(masses), tuple(inertials), tuple(collisions),
                geometry, path, hashlib.sha256(encoded).hexdigest(), sources, imu, framework_leg)


def load_spec(path: str | Path | None = None) -> Spec:
    """Load a spec file; ``None`` loads the OP2 spec shipped with op2motion (cached)."""
    if path is None:
        return default_spec()
    return parse_spec(read_text(path, "spec file", SpecError), str(path))


def spec_text(path: str | Path | None = None) -> str:
    """The TOML text of a spec file (``None``: the shipped OP2 spec), e.g. to send to another machine."""
    return _shipped_spec_text() if path is None else read_text(path, "spec file", SpecError)


def _shipped_spec_text() -> str:
    """``specs/op2.toml``: installed as package data ``op2motion.specs``, or beside the package in a source tree."""
    source_tree = Path(__file__).resolve().parents[2] / "specs" / "op2.toml"
    if source_tree.is_file():
        return source_tree.read_text(encoding="utf-8")
    try:
        return resources.files("op2motion.specs").joinpath("op2.toml").read_text(encoding="utf-8")
    except (ModuleNotFoundError, OSError) as exc:
        raise SpecError(f"the shipped spec is missing from this installation ({exc})", "specs/op2.toml") from None


@functools.lru_cache(maxsize=1)
def default_spec() -> Spec:
    """The shipped OP2 spec (``specs/op2.toml``), loaded once."""
    return parse_spec(_shipped_spec_text(), "specs/op2.toml")
