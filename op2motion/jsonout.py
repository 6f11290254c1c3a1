"""The one JSON encoder: every figure a command prints with ``--json`` (and every JSON file op2motion writes of its
results) goes through :func:`to_json`, with one rounding policy (:data:`SIGNIFICANT_DIGITS`).

Builders of a result's JSON return a :data:`JsonObject` (typed: its values are JSON values, not ``Any``) and leave
rounding to the encoder: a figure is computed at full precision and rounded once, where it leaves the program.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import PurePath
from typing import TypeAlias, Union

#: A JSON value (arrays and objects as read-only views, so that a ``list[float]`` or a ``dict[str, float]`` is one).
Json: TypeAlias = Union[None, bool, int, float, str, Sequence["Json"], Mapping[str, "Json"]]
#: A JSON object (what every ``as_dict`` and result summary returns).
JsonObject: TypeAlias = dict[str, Json]

#: The one rounding policy: a float leaves the program with this many significant digits (a length of 0.1 m to
#: 0.1 µm, an angle of 100° to 0.001°: beyond what the robot, the engines or the servo model resolve).
SIGNIFICANT_DIGITS = 6


def rounded(x: float) -> float:
    """``x`` with :data:`SIGNIFICANT_DIGITS` significant digits (non-finite values unchanged: the printer refuses
    them)."""
    if not math.isfinite(x) or x == 0.0:
        return float(x)
    return float(f"{x:.{SIGNIFICANT_DIGITS}g}")


def to_json(value: object) -> Json:
    """``value`` as a JSON value: mappings as objects (keys as text), sequences and arrays as lists, dataclasses as
    objects of their fields, NumPy scalars as numbers, paths as text, every float :func:`rounded`.

    Raises:
        TypeError: ``value`` holds something JSON has no form for (a programming error, not bad input).
    """
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return rounded(value)
    if isinstance(value, Mapping):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json(v) for v in value]
    if "numpy" in sys.modules:                  # a NumPy value exists only once NumPy is loaded (--help loads none)
        import numpy as np

        if isinstance(value, (np.ndarray, np.generic)):
            return to_json(value.tolist())
    if isinstance(value, PurePath):
        return str(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_json(getattr(value, f.name)) for f in dataclasses.fields(value)}
    raise TypeError(f"expected a value JSON can hold, got {type(value).__name__}")


def json_object(value: object) -> JsonObject:
    """``value`` (a mapping or a dataclass) as a JSON object, through :func:`to_json`.

    Raises:
        TypeError: ``value`` is not an object in JSON.
    """
    out = to_json(value)
    if not isinstance(out, dict):
        raise TypeError(f"expected an object for JSON, got {type(value).__name__}")
    return out
