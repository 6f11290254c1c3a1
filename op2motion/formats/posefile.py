"""Pose files (``poses/NAME.json``, schema ``op2motion.pose/1``): read with validation, write atomically.

A pose file holds the 20 servo angles by official joint name (degrees, the authoritative field), the support
foot, the book's variables (degrees, for humans), metrics and provenance. Readers reject unknown schema
versions, unknown or missing joints, non-finite angles, angles outside the joints' limits and invalid names.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from op2motion.errors import InputError, PoseFileError
from op2motion.fileio import read_text, write_atomic
from op2motion.robot.joints import BookAngles, servo_dict, servo_from_mapping
from op2motion.robot.pose import Pose
from op2motion.robot.spec import Spec
from op2motion.version import __version__

SCHEMA = "op2motion.pose/1"
BOOK_AGREEMENT_DEG = 1e-6  # book_deg and servo_deg of one file must agree to this [deg]


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
    """Check and write a pose file atomically."""
    pose.checked(spec, str(path))
    return write_atomic(path, pose_to_json(pose, spec))


def parse_pose(doc: Any, spec: Spec, where: str = "<pose>") -> Pose:
    """Check a decoded pose document and return its :class:`Pose`; errors are :class:`PoseFileError` naming
    ``where`` and the field."""
    if not isinstance(doc, dict):
        raise PoseFileError(f"expected a JSON object, got {type(doc).__name__}", where)
    schema = doc.get("schema")
    if schema != SCHEMA:
        raise PoseFileError(f"schema: expected {SCHEMA!r}, got {schema!r}", where)
    unknown = set(doc) - POSE_KEYS
    if unknown:
        raise PoseFileError(f"unknown field(s) {', '.join(sorted(unknown))} (expected some of "
                            f"{', '.join(sorted(POSE_KEYS))})", where)
    try:
        servo = servo_from_mapping(doc.get("servo_deg"), spec)  # type: ignore[arg-type]
        pose = Pose(doc.get("name"), doc.get("support"), servo, _mapping(doc, "metrics"),  # type: ignore[arg-type]
                    _mapping(doc, "provenance")).checked(spec)
        book = doc.get("book_deg")
        if book is not None:
            _check_book(book, pose, spec)
    except InputError as exc:
        field = {"servo angles": "servo_deg"}.get(exc.param or "", exc.param)
        raise PoseFileError(f"{field}: {exc.message}" if field else exc.message, where) from None
    return pose


POSE_KEYS = {"schema", "name", "support", "servo_deg", "book_deg", "metrics", "provenance"}


class DuplicateKey(ValueError):
    """A JSON object names one key twice (JSON decoders keep the last silently)."""

    def __init__(self, key: str):
        super().__init__(key)
        self.key = key


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise DuplicateKey(key)
        out[key] = value
    return out


def read_json_file(path: str | Path, what: str) -> Any:
    """The decoded JSON of a pose or motion file; unreadable files and bad JSON are :class:`PoseFileError`."""
    text = read_text(path, what, PoseFileError)
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except DuplicateKey as exc:
        raise PoseFileError(f"expected each key once in an object, got {exc.key!r} twice", str(path)) from None
    except json.JSONDecodeError as exc:
        raise PoseFileError(f"not valid JSON: {exc.msg} at line {exc.lineno}", str(path)) from None
    except RecursionError:
        raise PoseFileError("not valid JSON: nested too deeply", str(path)) from None


def read_pose(path: str | Path, spec: Spec) -> Pose:
    """Read and check a pose file."""
    return parse_pose(read_json_file(path, "pose file"), spec, str(path))


def _mapping(doc: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise InputError(f"expected an object, got {type(value).__name__}", key)
    return value


def _check_book(book: Any, pose: Pose, spec: Spec) -> None:
    if not isinstance(book, dict):
        raise InputError("expected an object with th, phi, psi", "book_deg")
    try:
        given = BookAngles.from_deg(book.get("th"), book.get("phi"), book.get("psi"), pose.stance)
    except InputError as exc:
        raise InputError(f"{exc.param}: {exc.message}", "book_deg") from None
    diff = float(np.max(np.abs(given.vector() - pose.book(spec).vector())))
    if math.degrees(diff) > BOOK_AGREEMENT_DEG:
        raise InputError(f"disagrees with servo_deg by {math.degrees(diff):.6f}°", "book_deg")
