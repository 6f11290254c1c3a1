"""Which feet carry the robot: the typed :class:`Support`, its feet, stance and swing, and the polygon they span.

A pose stands on the ``left`` foot, the ``right`` foot or on both (``double``). The *stance* foot is the one the
world frame is rooted on (book fig. 2.17: the support sole's centre, X forward, Y left, Z up): the support foot,
or the left one for double support. A foot counts as lifted (not supporting) when its lowest corner is more than
:data:`LIFTED_M` above the floor: the one threshold the optimiser, the motion planner, the gait and the physics
judge share. The support polygon is the convex hull of the soles that carry the robot.

:class:`Support` is a ``str`` enum, so it compares equal to, hashes like and serialises as its value: files and
JSON keep the plain words.
"""

from __future__ import annotations

from enum import Enum
from typing import Iterable, Mapping

import numpy as np

from op2motion.errors import InputError
from op2motion.robot.balance import convex_hull
from op2motion.robot.sides import SIDES as SIDES
from op2motion.robot.sides import Side as Side
from op2motion.robot.sides import SupportName as SupportName
from op2motion.robot.sides import as_side as as_side

LIFTED_M = 0.005     # a foot whose lowest corner is this far above the floor is lifted: it does not support


def other_side(side: Support | Side) -> Side:
    """``left`` -> ``right`` and back."""
    return "right" if side == "left" else "left"


class Support(str, Enum):
    """The feet that carry the robot: one foot or both."""

    LEFT = "left"
    RIGHT = "right"
    DOUBLE = "double"

    _value_: SupportName

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    @classmethod
    def of(cls, value: object, param: str = "support") -> "Support":
        """``value`` as a support (``left``, ``right`` or ``double``); anything else is an :class:`InputError`."""
        try:
            return cls(value)
        except ValueError:
            raise InputError(f"expected one of {', '.join(s.value for s in cls)}, got {value!r}", param) from None

    @classmethod
    def single(cls, value: object, param: str = "support") -> "Support":
        """``value`` as a one-foot support (``left`` or ``right``)."""
        return cls(as_side(value, param))

    @property
    def is_double(self) -> bool:
        """Both feet carry the robot."""
        return self._value_ == "double"          # (the value, not the member: judging a run asks thousands of times)

    @property
    def feet(self) -> tuple[Side, ...]:
        """The feet on the floor: both for double support."""
        return _FEET[self._value_]

    @property
    def stance(self) -> Side:
        """The foot the world frame is rooted on: the support foot, the left one for double support."""
        return "right" if self._value_ == "right" else "left"

    @property
    def swing(self) -> Side | None:
        """The lifted foot of a one-foot support (None on two feet)."""
        return None if self.is_double else other_side(self.stance)

    def polygon(self, corners: Mapping[Side, np.ndarray] | Mapping[str, np.ndarray]) -> np.ndarray:
        """The support polygon (m, 2) [m], counter-clockwise: the convex hull of the supporting feet's sole corners,
        given per side as (k, 2) or (k, 3) points (only x and y are used)."""
        return convex_hull(np.vstack([np.asarray(corners[side])[:, :2] for side in self.feet]))


_FEET: dict[str, tuple[Side, ...]] = {"left": ("left",), "right": ("right",), "double": SIDES}


def fixed_foot(supports: Iterable[Support | SupportName]) -> Side:
    """The foot that stays on the floor in every one of ``supports`` (the left one when both do, or none does)."""
    common = set.intersection(*(set(Support.of(s).feet) for s in supports))
    return "left" if "left" in common or not common else "right"
