"""The one shape every user task returns: :class:`TaskResult`.

A task (one function per thing a user asks for: play a page, plan a motion, move a hand in a line, ...) takes a typed
request and returns a frozen :class:`TaskResult`: whether the answer is yes (``ok``), the one phrase that says why
not (``problem``), what the user should know anyway (``warnings``), the files it would write (``outputs``: written by
the caller, and only when ``ok``), its figures for a program (:meth:`TaskResult.as_dict`, what ``--json`` prints)
and for a person (``lines``). A "no" is a result, never an exception; exceptions are for bad input and faults.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Mapping


@dataclass(frozen=True)
class Output:
    """A file a task would write: where (``path``, as the user named it), what (text or bytes), and the name its path
    has in the report's ``files`` (``label``; None: its role)."""

    path: str
    content: str | bytes
    label: str | None = None


@dataclass(frozen=True)
class TaskResult:
    """What a task found (see the module docstring).

    Attributes:
        ok: The answer is yes (the check passed; nothing refused it).
        problem: When not ``ok``: the one phrase that says why (None otherwise).
        warnings: What the user should know before trusting the result (None: the task has no warnings to report;
            an empty tuple: it has, and there are none).
        outputs: The files to write when ``ok``, by role (``plot``, ``csv``, ``out``, ...).
        data: The task's figures (JSON-ready; no files, no warnings: :meth:`as_dict` adds them).
        lines: The result for a person, one line each.
        checked: False when the task was refused before its checks ran (then there is nothing to report but
            ``problem``).
        file_keys: Where :meth:`as_dict` puts the paths written: None, a ``files`` object {role: path}; else
            {role: JSON key} (a command whose report names its one file by its own key, ``validate``'s ``png``).
        files_on_no: Whether a "no" reports its (empty) ``files`` too (``optimize``'s report of an unreached target
            has none).
        interrupted: The "no" is a stop the user asked for (Ctrl-C, SIGTERM: exit 130), not a failed check.
    """

    ok: bool
    problem: str | None = None
    warnings: tuple[str, ...] | None = None
    outputs: Mapping[str, Output] = field(default_factory=lambda: MappingProxyType({}))
    data: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    lines: tuple[str, ...] = ()
    checked: bool = True
    file_keys: Mapping[str, str] | None = None
    files_on_no: bool = True
    interrupted: bool = False

    def __post_init__(self) -> None:
        if self.ok == (self.problem is not None):
            raise ValueError(f"expected a problem exactly when not ok, got ok={self.ok} and problem={self.problem!r}")
        object.__setattr__(self, "outputs", MappingProxyType(dict(self.outputs)))
        object.__setattr__(self, "data", MappingProxyType(dict(self.data)))

    @classmethod
    def refused(cls, problem: str) -> "TaskResult":
        """A task refused before its checks ran (e.g. goals a servo cannot reach)."""
        return cls(False, problem, checked=False)

    def with_warnings(self, warnings: tuple[str, ...] | None) -> "TaskResult":
        """This result with ``warnings`` (as the caller words them, e.g. with its flags)."""
        return replace(self, warnings=warnings)

    def as_dict(self, files: Mapping[str, str] | None = None) -> dict[str, Any]:
        """The figures as JSON: ``data``, then ``warnings`` (unless the task has none to report) and ``files`` (role
        -> path written; given by the caller once it has written them, empty when nothing was)."""
        out = dict(self.data)
        if self.warnings is not None:
            out["warnings"] = list(self.warnings)
        written = dict(files or {})
        if self.file_keys is None and (self.ok or self.files_on_no):
            out["files"] = {(self.outputs[role].label if role in self.outputs else None) or role: path
                            for role, path in written.items()}
        elif self.file_keys is not None:
            out.update({key: written[role] for role, key in self.file_keys.items() if role in written})
        return out
