"""The one shape every user task returns: :class:`TaskResult`.

A task (one function per thing a user asks for: play a page, plan a motion, move a hand in a line, ...) takes a typed
request and returns a frozen :class:`TaskResult`: whether the answer is yes (``ok``), the one phrase that says why
not (``problem``), what the user should know anyway (``warnings``), the files it would write (``outputs``: written by
the caller, and only when ``ok``), its figures for a program (:meth:`TaskResult.as_dict`, what ``--json`` prints,
made by the one JSON encoder) and for a person (``lines``). A "no" is a result, never an exception; exceptions are
for bad input and faults.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Generic, Mapping, TypeVar

from op2motion.jsonout import Json, JsonObject, json_object


@dataclass(frozen=True)
class Output:
    """A file a task would write: where (``path``, as the user named it), what (text or bytes), and where the report
    names it once written: under its own top-level ``key`` (``validate``'s ``png``), else in the report's ``files``
    object by ``label`` (None: its role) when the task's figures have one (its data holds ``"files": {}``), else
    not at all (the task's figures name it already, e.g. as ``path``)."""

    path: str
    content: str | bytes
    label: str | None = None
    key: str | None = None


#: What a task found, typed (a check's report, a solved pose, a plan, ...).
T = TypeVar("T")


@dataclass(frozen=True)
class TaskResult(Generic[T]):
    """What a task found (see the module docstring), with its typed ``value`` for programs.

    Attributes:
        ok: The answer is yes (the check passed; nothing refused it).
        problem: When not ``ok``: the one phrase that says why (None otherwise).
        warnings: What the user should know before trusting the result (None: the task has no warnings to report;
            an empty tuple: it has, and there are none).
        outputs: The files to write when ``ok``, by role (``plot``, ``csv``, ``out``, ...).
        data: The task's figures as JSON (made by :func:`op2motion.jsonout.json_object`: rounded once; no
            warnings: :meth:`as_dict` adds them; ``"files": {}`` where the report lists the files written).
        lines: The result for a person, one line each.
        checked: False when the task was refused before its checks ran (then there is nothing to report but
            ``problem``).
        interrupted: The "no" is a stop the user asked for (Ctrl-C, SIGTERM: exit 130), not a failed check.
        value: What the task found, typed (e.g. ``validate``'s :class:`~op2motion.physics.CheckReport`); None when
            it was refused before it ran.
    """

    ok: bool
    problem: str | None = None
    warnings: tuple[str, ...] | None = None
    outputs: Mapping[str, Output] = field(default_factory=lambda: MappingProxyType({}))
    data: Mapping[str, Json] = field(default_factory=lambda: MappingProxyType({}))
    lines: tuple[str, ...] = ()
    checked: bool = True
    interrupted: bool = False
    value: T | None = None

    def __post_init__(self) -> None:
        if self.ok == (self.problem is not None):
            raise ValueError(f"expected a problem exactly when not ok, got ok={self.ok} and problem={self.problem!r}")
        object.__setattr__(self, "outputs", MappingProxyType(dict(self.outputs)))
        object.__setattr__(self, "data", MappingProxyType(json_object(self.data)))

    @classmethod
    def refused(cls, problem: str) -> TaskResult[Any]:
        """A task refused before its checks ran (e.g. goals a servo cannot reach)."""
        return cls(False, problem, checked=False)

    def with_warnings(self, warnings: tuple[str, ...] | None) -> TaskResult[T]:
        """This result with ``warnings`` (as the caller words them, e.g. with its flags)."""
        return replace(self, warnings=warnings)

    def as_dict(self, files: Mapping[str, str] | None = None) -> JsonObject:
        """The figures as JSON: ``data``, then ``warnings`` (unless the task has none to report) and the paths of the
        ``files`` written (role -> path; given by the caller once it has written them) where each output says."""
        out = dict(self.data)
        listed = out.pop("files", None)
        if self.warnings is not None:
            out["warnings"] = list(self.warnings)
        listed = dict(listed) if isinstance(listed, dict) else None
        for role, path in (files or {}).items():
            made = self.outputs.get(role)
            if made is not None and made.key is not None:
                out[made.key] = path
            elif listed is not None:
                listed[(made.label if made is not None else None) or role] = path
        if listed is not None:
            out["files"] = listed
        return out
