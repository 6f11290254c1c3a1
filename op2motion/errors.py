"""The one error hierarchy of op2motion.

Every error a user can cause derives from :class:`Op2MotionError`. An error names the *parameter* it is about
(``param``, a library name such as ``seconds`` or ``br``) separately from its message, so that the command line
can show the flag the user typed (``--seconds``) while library users see the parameter name; a message that points
at another parameter does so with :func:`ref`, shown the same way. Errors carry their
data as attributes (e.g. :class:`Unreachable` has ``residual_m`` and ``tolerance_m``). The CLI prints one line on
stderr and exits with ``error.exit_code``: 2 for bad input, 1 for a check that ran and failed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable, Literal

from op2motion.jsonout import JsonObject

#: A joint range: the ``mechanical`` (hard) stops or the ``cable-safe`` (advice) range.
LimitKind = Literal["mechanical", "cable-safe"]
_REF = re.compile(r"\{param:(\w+)\}")


def ref(param: str) -> str:
    """A reference to library parameter ``param`` inside a message: shown as the parameter's name to library users
    and as the flag that sets it on the command line (:func:`render_refs`)."""
    return "{param:" + param + "}"


def shown(text: str) -> str:
    """``text`` (a path, a name the user typed) as a message quotes it: as it is when it prints on one line, else
    quoted with Python's escapes (``'/dev/tty\\nUSB0'``) so that the message stays one line and shows what came."""
    return text if text.isprintable() and text == text.strip() else repr(text)


def one_line(text: str) -> str:
    """``text`` with every character that would break or hide a line (newline, carriage return, other controls,
    Unicode line separators) escaped as Python writes it: what the command line prints is always one line."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def render_refs(text: str, name_of: Callable[[str], str] = lambda p: p) -> str:
    """``text`` with each :func:`ref` shown through ``name_of``."""
    return _REF.sub(lambda m: name_of(m.group(1)), text)


class Op2MotionError(Exception):
    """Base class of every op2motion error (bad input: exit code 2).

    Args:
        message: what was expected and what came, without the parameter name.
        param: the library parameter the error is about (``None`` when it is about no single parameter).
    """

    exit_code: int = 2

    def __init__(self, message: str, param: str | None = None):
        super().__init__(message)
        self.message, self.param = message, param

    def render(self, name_of: Callable[[str], str] = lambda p: p) -> str:
        """One line: ``<name>: <message>``, the parameter shown through ``name_of`` (the CLI maps it to a flag)."""
        message = render_refs(self.message, name_of)
        return f"{name_of(self.param)}: {message}" if self.param else message

    def __str__(self) -> str:
        return self.render()


class SpecError(Op2MotionError):
    """The robot spec file is missing, unreadable, malformed or physically inconsistent."""


class InputError(Op2MotionError):
    """A value, angle vector, name or path given by the user is malformed or out of range."""


class PoseFileError(Op2MotionError):
    """A pose file cannot be read: bad JSON, unknown schema version, unknown joints, angles out of range."""


class ModelError(Op2MotionError):
    """A kinematic model was asked for something it cannot represent (e.g. psi != 0 in the projection model)."""


class OutputError(InputError):
    """An output path cannot be written (a directory, a read-only folder, an empty name, held by another run)."""


class CheckFailed(Op2MotionError):
    """A check ran and its verdict is negative (unstable pose, unreachable target): exit code 1."""

    exit_code = 1


class PortFailed(CheckFailed):
    """The robot's serial port stopped working (unplugged, hung up, an I/O or terminal error, stuck): exit code 1."""


class Interrupted(Op2MotionError):
    """The user interrupted a run (Ctrl-C, SIGTERM) after it put its files in order: exit code 130."""

    exit_code = 130


class Unreachable(CheckFailed):
    """A target was not reached: the best residual [m] exceeds the tolerance [m]."""

    def __init__(self, message: str, residual_m: float, tolerance_m: float):
        super().__init__(message)
        self.residual_m, self.tolerance_m = residual_m, tolerance_m


@dataclass(frozen=True)
class LimitViolation:
    """One joint of one pose outside a range: its value and the range [deg] (degrees: it is shown to people)."""

    joint: str
    value_deg: float
    lower_deg: float
    upper_deg: float
    kind: LimitKind = "mechanical"

    def describe(self) -> str:
        """``l_knee = -135.0° is outside its mechanical range [-130°, 6°]``."""
        return (f"{self.joint} = {self.value_deg:.1f}° is outside its {self.kind} range "
                f"[{self.lower_deg:g}°, {self.upper_deg:g}°]")

    def as_dict(self) -> JsonObject:
        """JSON-ready dict."""
        return {"joint": self.joint, "value_deg": self.value_deg, "lower_deg": self.lower_deg,
                "upper_deg": self.upper_deg, "kind": self.kind}


class LimitError(InputError):
    """Angles outside a joint range; ``violations`` lists every offending joint."""

    def __init__(self, where: str, violations: list[LimitViolation]):
        super().__init__(f"{violations[0].describe()}" + (f" (and {len(violations) - 1} more)"
                                                           if len(violations) > 1 else ""), where or None)
        self.violations = violations
