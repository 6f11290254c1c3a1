"""The one error hierarchy of op2motion.

Every error a user can cause derives from :class:`Op2MotionError`. The CLI prints ``str(error)`` as one line
on stderr and exits with ``error.exit_code``: 2 for bad input, 1 for a check that ran and failed.
"""

from __future__ import annotations


class Op2MotionError(Exception):
    """Base class of every op2motion error (bad input: exit code 2)."""

    exit_code: int = 2


class SpecError(Op2MotionError):
    """The robot spec file is missing, malformed or inconsistent."""


class InputError(Op2MotionError):
    """A command-line value, angle vector or pose is malformed (wrong count, NaN, unknown name, ...)."""


class PoseFileError(Op2MotionError):
    """A pose file cannot be read: bad JSON, unknown schema version, unknown joints, angles out of limits."""


class ModelError(Op2MotionError):
    """A kinematic model was asked for something it cannot represent (e.g. psi != 0 in the projection model)."""


class CheckFailed(Op2MotionError):
    """A check ran and its verdict is negative (unstable pose, unreachable target): exit code 1."""

    exit_code = 1
