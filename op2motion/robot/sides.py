"""The words for the sides of the body and for the feet that carry it, as types: :data:`Side`, :data:`SupportName`.

The lowest module of the robot package, so that the spec, the joints and the support can all name them. The
typed :class:`~op2motion.robot.support.Support` (a ``str`` enum) has the values of :data:`SupportName`.
"""

from __future__ import annotations

from typing import Literal, get_args

from op2motion.errors import InputError

#: A foot, a hand, a leg or an arm: which side of the body.
Side = Literal["left", "right"]
#: The feet that carry the robot, as a word (the value of a :class:`~op2motion.robot.support.Support`).
SupportName = Literal["left", "right", "double"]
SIDES = get_args(Side)   # typed tuple[Any, ...]: the many dicts keyed by side stay dict[str, ...]


def as_side(value: object, param: str = "side") -> Side:
    """``value`` as a side (``left`` or ``right``); anything else is an :class:`InputError` naming ``param``."""
    if value == "left":
        return "left"
    if value == "right":
        return "right"
    raise InputError(f"expected 'left' or 'right', got {value!r}", param)
