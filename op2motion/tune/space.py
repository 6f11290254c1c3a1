"""What a tuning study searches: named parameters, each over a range, sampled by Optuna.

A :class:`Param` is one setting with its range (``low`` to ``high``, optionally on a log scale or in steps); a
:class:`ParameterSpace` is an ordered set of them, plus the settings it may search but does not by default
(``optional``: ``--param`` adds one). :meth:`ParameterSpace.narrowed` takes the user's overrides
(``--param NAME LOW HIGH``): an unknown name, an empty or inverted range, a range outside what the setting allows,
or a non-finite bound is bad input naming the parameter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Iterable, Sequence

from op2motion.errors import InputError


@dataclass(frozen=True)
class Param:
    """One searched setting: ``name`` over ``low``..``high`` (``step``: a grid; ``log``: a log scale), within what
    the setting allows (``allowed``: (lowest, highest)); ``unit`` for people."""

    name: str
    low: float
    high: float
    unit: str = ""
    step: float | None = None
    log: bool = False
    allowed: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        lo, hi = self.allowed if self.allowed is not None else (self.low, self.high)
        if not all(math.isfinite(v) for v in (self.low, self.high)) or not self.low < self.high:
            raise InputError(f"expected a range low < high, got {self.low!r} to {self.high!r}", self.name)
        if not (lo <= self.low and self.high <= hi):
            raise InputError(f"expected a range within {lo:g} to {hi:g} {self.unit}".rstrip()
                             + f", got {self.low:g} to {self.high:g}", self.name)
        if self.log and self.low <= 0.0:
            raise InputError(f"expected a positive range for a log scale, got {self.low:g}", self.name)

    def sample(self, trial: Any) -> float:
        """This parameter's value for an Optuna ``trial``."""
        return float(trial.suggest_float(self.name, self.low, self.high, step=self.step, log=self.log))


@dataclass(frozen=True)
class ParameterSpace:
    """The parameters of a study, in order; ``optional``: those a ``--param`` may add (not searched by default)."""

    params: tuple[Param, ...]
    optional: tuple[Param, ...] = ()

    def __post_init__(self) -> None:
        names = [p.name for p in self.params]
        if not names or len(set(names)) != len(names):
            raise InputError(f"expected distinct parameters, got {names}", "param")

    @property
    def names(self) -> tuple[str, ...]:
        """The parameters' names."""
        return tuple(p.name for p in self.params)

    def sample(self, trial: Any) -> dict[str, float]:
        """One point {name: value} for an Optuna ``trial``."""
        return {p.name: p.sample(trial) for p in self.params}

    def narrowed(self, overrides: Iterable[Sequence[str]] = (), only: Sequence[str] | None = None) -> "ParameterSpace":
        """The space with ranges from ``overrides`` (NAME LOW HIGH, as typed) and, with ``only``, just those
        parameters (the others stay at the base setting)."""
        by_name = {p.name: p for p in self.params}
        extra = {p.name: p for p in self.optional}
        if only is not None:
            unknown = [n for n in only if n not in by_name]
            if unknown:
                raise InputError(f"expected parameters among {', '.join(by_name)}, got {', '.join(unknown)}", "param")
            by_name = {n: by_name[n] for n in only}
        for words in overrides:
            if len(words) != 3:
                raise InputError(f"expected NAME LOW HIGH, got {' '.join(words)}", "param")
            name, low, high = words
            if name not in by_name and name in extra:
                by_name[name] = extra[name]
            if name not in by_name:
                known = ", ".join([*by_name, *(n for n in extra if n not in by_name)])
                raise InputError(f"expected a parameter among {known}, got {name!r}", "param")
            try:
                lo, hi = float(low), float(high)
            except ValueError:
                raise InputError(f"expected two numbers after {name}, got {low!r} {high!r}", "param") from None
            base = by_name[name]
            by_name[name] = replace(base, low=lo, high=hi, allowed=base.allowed or (base.low, base.high))
        return ParameterSpace(tuple(by_name.values()))
