"""Strict access to one TOML table: typed getters whose errors name the file and the key, and a check that no
unknown key was left unread. Used by the spec loader."""

from __future__ import annotations

import math
from typing import Any

from op2motion.errors import SpecError


class TableReader:
    """Strict accessor for one TOML table: every key read once, unknown keys reported."""

    def __init__(self, path: str, where: str, table: Any):
        if not isinstance(table, dict):
            raise SpecError(f"{path}: {where}: expected a table, got {type(table).__name__}")
        self.path, self.where, self.table = path, where, table
        self.used: set[str] = set()

    def _key(self, key: str) -> str:
        return f"{self.where}.{key}" if self.where else key

    def get(self, key: str, kind: type | tuple[type, ...]) -> Any:
        if key not in self.table:
            raise SpecError(f"{self.path}: missing key {self._key(key)!r}")
        value = self.table[key]
        self.used.add(key)
        kinds = kind if isinstance(kind, tuple) else (kind,)
        if float in kinds and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if isinstance(value, bool) or not isinstance(value, kinds):
            names = "/".join(k.__name__ for k in kinds)
            raise SpecError(f"{self.path}: {self._key(key)}: expected {names}, got {value!r}")
        return value

    def number(self, key: str, positive: bool = False, nonnegative: bool = False) -> float:
        value: float = self.get(key, float)
        if not math.isfinite(value) or (positive and value <= 0) or (nonnegative and value < 0):
            need = "a positive number" if positive else "a non-negative number" if nonnegative else "a finite number"
            raise SpecError(f"{self.path}: {self._key(key)}: expected {need}, got {value!r}")
        return value

    def vector(self, key: str, n: int = 3) -> tuple[float, ...]:
        value = self.get(key, list)
        if len(value) != n or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            raise SpecError(f"{self.path}: {self._key(key)}: expected {n} numbers, got {value!r}")
        if not all(math.isfinite(v) for v in value):
            raise SpecError(f"{self.path}: {self._key(key)}: expected finite numbers, got {value!r}")
        return tuple(float(v) for v in value)

    def sub(self, key: str) -> "TableReader":
        return TableReader(self.path, self._key(key), self.get(key, dict))

    def array(self, key: str) -> list["TableReader"]:
        items = self.get(key, list)
        return [TableReader(self.path, f"{self._key(key)}[{i}]", t) for i, t in enumerate(items)]

    def done(self) -> None:
        unknown = sorted(set(self.table) - self.used)
        if unknown:
            raise SpecError(f"{self.path}: unknown key {self._key(unknown[0])!r}")
