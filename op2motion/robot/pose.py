"""The whole-body pose: 20 servo angles [rad] by Dynamixel ID, the support, a name, metrics and provenance.

:class:`Pose` sits below every module that uses poses (optimiser workflow, physics, files, motions), so none of
them depends on a file format. Its checks: the support is ``left``, ``right`` or ``double``; the angles are 20
finite numbers within the joints' limits; the name is a *pose name*: letters, digits, ``-``, ``_`` and ``.``, at
most :data:`MAX_NAME_LEN` characters, not starting with a dot, so that a file name made from it stays inside its
folder.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from op2motion.errors import InputError, LimitError
from op2motion.robot.joints import BookAngles, book_to_servo, limit_violations, servo_to_book
from op2motion.robot.spec import Spec
from op2motion.robot.support import Side, Support

MAX_NAME_LEN = 100
_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9_.-]*")
NAME_RULE = "letters, digits, '-', '_' and '.', not starting with '.', at most 100 characters"


def check_pose_name(name: object, param: str = "name") -> str:
    """Return ``name`` if it is a valid pose name (see the module docstring), else raise :class:`InputError`."""
    if not isinstance(name, str) or not _NAME.fullmatch(name) or len(name) > MAX_NAME_LEN:
        raise InputError(f"expected a pose name ({NAME_RULE}), got {name!r}", param)
    return name


def safe_pose_name(text: str, fallback: str) -> str:
    """A valid pose name made from free text (e.g. an action page's name): other characters become ``_``."""
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", text.strip()).lstrip(".")[:MAX_NAME_LEN]
    return name or fallback


@dataclass(frozen=True)
class Pose:
    """One whole-body pose: servo angles (20,) [rad] in ID order, support, metrics and provenance."""

    name: str
    support: Support
    servo: np.ndarray
    metrics: Mapping[str, Any] = field(default_factory=dict)
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "support", Support.of(self.support))

    @property
    def stance(self) -> Side:
        """The foot the world frame is rooted on (the left foot for double support)."""
        return self.support.stance

    def book(self, spec: Spec) -> BookAngles:
        """Book variables seen from :attr:`stance`."""
        return servo_to_book(self.servo, self.stance, spec)

    @classmethod
    def from_book(cls, name: str, angles: BookAngles, spec: Spec, **extra: Any) -> "Pose":
        """A pose from book variables (first pose of the batch); support = the batch's support foot."""
        return cls(name, angles.support, book_to_servo(angles.row(0), spec)[0], **extra)

    def checked(self, spec: Spec, where: str = "") -> "Pose":
        """Check name, support, angle count, finiteness and joint limits; returns ``self``."""
        check_pose_name(self.name)
        servo = np.asarray(self.servo, dtype=float)
        if servo.shape != (len(spec.joints),) or not np.all(np.isfinite(servo)):
            raise InputError(f"expected {len(spec.joints)} finite servo angles, got shape {servo.shape}",
                             where or "servo angles")
        bad = limit_violations(servo, spec)
        if bad:
            raise LimitError(where, bad)
        return self
