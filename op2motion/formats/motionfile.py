"""Motion files (``poses/motions/NAME.json``, schema ``op2motion.motion/1``): a pose sequence to plan and check.

A motion file holds ordered steps; each names a pose file (``"pose"``: a path relative to the motion file) or
carries the pose inline (``"servo_deg"`` by official joint name with ``"support"``), with ``duration_s`` (the time
to reach it from the previous step; absent for the first), ``pause_s`` (how long it is held, default 0) and an
optional ``support`` that overrides the pose's. ``profile`` (``quintic`` or ``robot``) and ``p_gain`` (the servos'
P gain, default 32) say how it is played. Readers reject unknown schemas and fields, and a failed write leaves the
old file in place (written atomically).

    {"schema": "op2motion.motion/1", "name": "stand_to_book_2_44", "profile": "quintic", "p_gain": 32,
     "steps": [{"pose": "../init.json"}, {"pose": "../book_2_44.json", "duration_s": 1.5, "pause_s": 0.5},
               {"pose": "../init.json", "duration_s": 1.5}]}
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, Sequence, get_args

from op2motion.errors import InputError, Op2MotionError, PoseFileError
from op2motion.fileio import read_bytes, write_atomic
from op2motion.formats.posefile import read_json_file, read_pose
from op2motion.robot.framework import DEFAULT_P_GAIN, MAX_MOTION_POSES, MAX_MOTION_S, MAX_SEGMENT_S, MIN_SEGMENT_S
from op2motion.robot.joints import servo_dict, servo_from_mapping
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.robot.support import Support
from op2motion.version import __version__

SCHEMA = "op2motion.motion/1"
#: How a motion moves between poses: a quintic in time, or as the robot's firmware plays a page.
Profile = Literal["quintic", "robot"]
#: A colliding straight segment: planned around in joint space (our RRT-Connect, ``rrt``, or OMPL's, ``ompl``), or
#: refused (``none``).
PlannerName = Literal["rrt", "ompl", "none"]
PROFILES: tuple[Profile, ...] = get_args(Profile)
PLANNERS: tuple[PlannerName, ...] = get_args(PlannerName)
_STEP_KEYS = {"pose", "name", "servo_deg", "support", "duration_s", "pause_s"}
_TOP_KEYS = {"schema", "name", "profile", "p_gain", "steps", "provenance"}


@dataclass(frozen=True)
class MotionStep:
    """One step: the pose (its servo angles [rad] and support), where it came from (a pose file path as written,
    or None inline), the time to reach it [s] and the pause after it [s]."""

    pose: Pose
    source: str | None
    duration_s: float
    pause_s: float


@dataclass(frozen=True)
class Motion:
    """A named pose sequence with its profile and P gain."""

    name: str
    steps: tuple[MotionStep, ...]
    profile: Profile = "quintic"
    p_gain: int = DEFAULT_P_GAIN


MAX_NAME_CHARS = 100


def check_motion_name(name: object, param: str = "name") -> str:
    """A motion's name: one line of at most :data:`MAX_NAME_CHARS` characters, no control characters (a file
    op2motion writes must read back)."""
    if not isinstance(name, str) or not name.strip() or len(name) > MAX_NAME_CHARS or any(
            ord(c) < 32 or ord(c) == 127 for c in name):
        raise InputError(f"expected a one-line name of 1 to {MAX_NAME_CHARS} characters without control "
                         f"characters, got {name!r}", param)
    return name


def _number(value: Any, what: str, where: str, low: float = 0.0) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or not low - 1e-9 <= value <= MAX_SEGMENT_S:
        raise PoseFileError(f"{what}: expected {low:g} to {MAX_SEGMENT_S:g} s, got {value!r}", where)
    return float(value)


def _step(doc: Any, k: int, base: Path, spec: Spec, where: str) -> MotionStep:
    at = f"{where}: steps[{k}]"
    if not isinstance(doc, dict):
        raise PoseFileError(f"expected an object, got {type(doc).__name__}", at)
    unknown = set(doc) - _STEP_KEYS
    if unknown:
        raise PoseFileError(f"unknown field(s) {', '.join(sorted(unknown))}", at)
    if ("pose" in doc) == ("servo_deg" in doc):
        raise PoseFileError("expected either 'pose' (a pose file) or 'servo_deg' (inline angles)", at)
    if "pose" in doc:
        if not isinstance(doc["pose"], str):
            raise PoseFileError(f"pose: expected a path, got {doc['pose']!r}", at)
        pose = read_pose(base / doc["pose"], spec)
        source: str | None = doc["pose"]
    else:
        support = doc.get("support", "double")
        Support.of(support)
        pose = Pose(doc.get("name", f"step{k}"), support, servo_from_mapping(doc["servo_deg"], spec), {},
                    {"source": f"{where} step {k}"}).checked(spec, at)
        source = None
    if "support" in doc and "pose" in doc:
        Support.of(doc["support"])
        pose = Pose(pose.name, doc["support"], pose.servo, pose.metrics, pose.provenance)
    if k == 0 and "duration_s" in doc:
        raise PoseFileError("duration_s: the first step is where the motion starts (no duration)", at)
    if k > 0 and "duration_s" not in doc:
        raise PoseFileError("duration_s: expected the time to reach this pose [s]", at)
    duration = _number(doc["duration_s"], "duration_s", at, MIN_SEGMENT_S) if k else 0.0
    return MotionStep(pose, source, duration, _number(doc.get("pause_s", 0.0), "pause_s", at))


def parse_motion(doc: Any, spec: Spec, base: Path, where: str = "<motion>") -> Motion:
    """Check a decoded motion document; pose paths are relative to ``base``."""
    if not isinstance(doc, dict):
        raise PoseFileError(f"expected a JSON object, got {type(doc).__name__}", where)
    if doc.get("schema") != SCHEMA:
        raise PoseFileError(f"schema: expected {SCHEMA!r}, got {doc.get('schema')!r}", where)
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise PoseFileError(f"unknown field(s) {', '.join(sorted(unknown))}", where)
    name, profile, gain = doc.get("name"), doc.get("profile", "quintic"), doc.get("p_gain", 32)
    try:
        name = check_motion_name(name)
    except InputError as exc:
        raise PoseFileError(f"name: {exc.message}", where) from None
    if profile not in PROFILES:
        raise PoseFileError(f"profile: expected one of {', '.join(PROFILES)}, got {profile!r}", where)
    if isinstance(gain, bool) or not isinstance(gain, int) or not 1 <= gain <= 254:
        raise PoseFileError(f"p_gain: expected an integer 1..254, got {gain!r}", where)
    steps = doc.get("steps")
    if not isinstance(steps, list) or not 2 <= len(steps) <= MAX_MOTION_POSES:
        raise PoseFileError(f"steps: expected a list of 2 to {MAX_MOTION_POSES} steps", where)
    motion = Motion(name, tuple(_step(s, k, base, spec, where) for k, s in enumerate(steps)), profile, gain)
    total = sum(s.duration_s + s.pause_s for s in motion.steps)
    if total > MAX_MOTION_S:
        raise PoseFileError(f"steps: expected at most {MAX_MOTION_S:g} s in all (duration_s and pause_s), got "
                            f"{total:g} s", where)
    return motion


def read_motion(path: str | Path, spec: Spec) -> Motion:
    """Read and check a motion file."""
    return parse_motion(read_json_file(path, "motion file"), spec, Path(path).parent, str(path))


def is_motion_file(path: str | Path) -> bool:
    """Whether ``path`` holds a motion document (its schema names a motion, of any version), not a pose."""
    try:
        return str(json.loads(read_bytes(path, "pose or motion file")).get("schema")).startswith("op2motion.motion/")
    except (Op2MotionError, ValueError, AttributeError):
        return False


def motion_to_json(motion: Motion, spec: Spec, where: str | Path) -> str:
    """The motion file text for a file at ``where``: pose files referenced relative to it, inline poses in
    degrees."""
    steps = []
    for k, step in enumerate(motion.steps):
        item: dict[str, Any] = {}
        if step.source is not None:
            item["pose"] = step.source
        else:
            item.update(name=step.pose.name, support=step.pose.support,
                        servo_deg={n: round(v, 6) for n, v in servo_dict(step.pose.servo, spec).items()})
        if step.source is not None and step.pose.support != read_support(step, where, spec):
            item["support"] = step.pose.support
        if k:
            item["duration_s"] = round(step.duration_s, 6)
        if step.pause_s:
            item["pause_s"] = round(step.pause_s, 6)
        steps.append(item)
    doc = {"schema": SCHEMA, "name": motion.name, "profile": motion.profile, "p_gain": motion.p_gain,
           "steps": steps, "provenance": {"version": __version__, "spec_sha256": spec.sha256}}
    return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"


def read_support(step: MotionStep, where: str | Path, spec: Spec) -> str:
    """The support written in the pose file a step refers to (the motion file's folder need not exist yet: the
    reference is resolved by name)."""
    return read_pose(os.path.normpath(Path(os.path.abspath(where)).parent / str(step.source)), spec).support


def relative_source(pose_path: str | Path, motion_path: str | Path) -> str:
    """A pose file's path as a motion file at ``motion_path`` refers to it."""
    return Path(os.path.relpath(Path(pose_path).resolve(), Path(motion_path).resolve().parent)).as_posix()


def rebased(motion: Motion, old: str | Path, new: str | Path) -> Motion:
    """``motion`` read from ``old`` with its pose references rewritten for a motion file at ``new``."""
    steps = tuple(MotionStep(s.pose, None if s.source is None else relative_source(Path(old).parent / s.source, new),
                             s.duration_s, s.pause_s) for s in motion.steps)
    return Motion(motion.name, steps, motion.profile, motion.p_gain)


def write_motion(motion: Motion, path: str | Path, spec: Spec) -> Path:
    """Write a motion file atomically (its pose references must resolve from there)."""
    text = motion_to_json(motion, spec, path)
    parse_motion(json.loads(text), spec, Path(path).parent, str(path))
    return write_atomic(path, text)


def motion_of(poses: Sequence[Pose], sources: Sequence[str | None], durations: Sequence[float],
              pauses: Sequence[float], name: str, profile: Profile = "quintic",
              p_gain: int = DEFAULT_P_GAIN) -> Motion:
    """A motion from poses with their sources, the durations of the steps after the first and the pauses."""
    check_motion_name(name)
    if len(durations) != len(poses) - 1 or len(pauses) != len(poses):
        raise InputError(f"expected {len(poses) - 1} durations and {len(poses)} pauses for {len(poses)} poses, got "
                         f"{len(durations)} and {len(pauses)}", "durations")
    steps = tuple(MotionStep(p, s, 0.0 if k == 0 else float(durations[k - 1]), float(pauses[k]))
                  for k, (p, s) in enumerate(zip(poses, sources)))
    return Motion(name, steps, profile, p_gain)
