"""Pose files (``poses/NAME.json``, schema ``op2motion.pose/1``): read with validation, write atomically.

A pose file holds the 20 servo angles by official joint name (degrees, the authoritative field), the support
foot, the book's variables (degrees, for humans), metrics and provenance. Readers reject unknown schema
versions, unknown or missing joints, non-finite angles and angles outside the spec's cable-safe limits.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .. import __version__
from ..errors import InputError, PoseFileError
from ..fileio import write_atomic
from ..joints import BookAngles, book_to_servo, limit_violations, servo_dict, servo_from_mapping, servo_to_book
from ..spec import Spec

SCHEMA = "op2motion.pose/1"
POSE_SUPPORTS = ("left", "right", "double")
BOOK_AGREEMENT_DEG = 1e-6  # book_deg and servo_deg of one file must agree to this [deg]


@dataclass(frozen=True)
class Pose:
    """One whole-body pose: servo angles (20,) [rad] in ID order, support foot, metrics and provenance."""

    name: str
    support: str
    servo: np.ndarray
    metrics: Mapping[str, Any] = field(default_factory=dict)
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def book(self, spec: Spec) -> BookAngles:
        """Book variables seen from the support foot (the left foot for ``double`` support)."""
        return servo_to_book(self.servo, "right" if self.support == "right" else "left", spec)

    @classmethod
    def from_book(cls, name: str, angles: BookAngles, spec: Spec, **extra: Any) -> "Pose":
        """A pose from book variables (first pose of the batch)."""
        return cls(name, angles.support, book_to_servo(angles.row(0), spec)[0], **extra)


def pose_to_json(pose: Pose, spec: Spec) -> str:
    """The pose file text."""
    book = pose.book(spec).degrees()
    doc = {
        "schema": SCHEMA,
        "name": pose.name,
        "support": pose.support,
        "servo_deg": {k: round(v, 6) for k, v in servo_dict(pose.servo, spec).items()},
        "book_deg": {k: [round(v, 6) for v in vals] for k, vals in book.items()},
        "metrics": dict(pose.metrics),
        "provenance": {"version": __version__, "spec_sha256": spec.sha256, **dict(pose.provenance)},
    }
    return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"


def write_pose(pose: Pose, path: str | Path, spec: Spec) -> Path:
    """Validate and write a pose file atomically."""
    _check_limits(pose.servo, spec, str(path))
    return write_atomic(path, pose_to_json(pose, spec))


def parse_pose(doc: Any, spec: Spec, where: str = "<pose>") -> Pose:
    """Validate a decoded pose document."""
    if not isinstance(doc, dict):
        raise PoseFileError(f"{where}: expected a JSON object, got {type(doc).__name__}")
    schema = doc.get("schema")
    if schema != SCHEMA:
        raise PoseFileError(f"{where}: schema: expected {SCHEMA!r}, got {schema!r}")
    name, support = doc.get("name"), doc.get("support")
    if not isinstance(name, str) or not name:
        raise PoseFileError(f"{where}: name: expected a non-empty string, got {name!r}")
    if support not in POSE_SUPPORTS:
        raise PoseFileError(f"{where}: support: expected one of {', '.join(POSE_SUPPORTS)}, got {support!r}")
    try:
        servo = servo_from_mapping(doc.get("servo_deg"), spec)  # type: ignore[arg-type]
    except InputError as exc:
        raise PoseFileError(f"{where}: servo_deg: {exc}") from None
    _check_limits(servo, spec, where)
    pose = Pose(name, support, servo, _mapping(doc, "metrics", where), _mapping(doc, "provenance", where))
    book = doc.get("book_deg")
    if book is not None:
        _check_book(book, pose, spec, where)
    return pose


def read_pose(path: str | Path, spec: Spec) -> Pose:
    """Read and validate a pose file."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise PoseFileError(f"{p}: no such pose file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PoseFileError(f"{p}: cannot read pose file: {exc}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PoseFileError(f"{p}: not valid JSON: {exc.msg} at line {exc.lineno}") from None
    return parse_pose(doc, spec, str(p))


def _mapping(doc: Mapping[str, Any], key: str, where: str) -> Mapping[str, Any]:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise PoseFileError(f"{where}: {key}: expected an object, got {type(value).__name__}")
    return value


def _check_limits(servo: np.ndarray, spec: Spec, where: str) -> None:
    bad = limit_violations(servo, spec)
    if bad:
        b = bad[0]
        raise PoseFileError(f"{where}: {b['joint']} = {b['deg']}° is outside its limits "
                            f"[{b['lower_deg']}°, {b['upper_deg']}°]")


def _check_book(book: Any, pose: Pose, spec: Spec, where: str) -> None:
    if not isinstance(book, dict):
        raise PoseFileError(f"{where}: book_deg: expected an object with th, phi, psi")
    try:
        given = BookAngles.from_deg(book.get("th"), book.get("phi"), book.get("psi"), pose.book(spec).support)
    except InputError as exc:
        raise PoseFileError(f"{where}: book_deg: {exc}") from None
    derived = pose.book(spec)
    diff = float(np.max(np.abs(given.vector() - derived.vector())))
    if math.degrees(diff) > BOOK_AGREEMENT_DEG:
        raise PoseFileError(f"{where}: book_deg disagrees with servo_deg by {math.degrees(diff):.6f}°")
