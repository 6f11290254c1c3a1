"""The one way op2motion compiles a kernel: numba's ``njit`` with the on-disk cache and NumPy's error model, typed.

numba ships no type information, so ``@njit(...)`` would make every kernel an untyped function to mypy (and every
call of one unchecked). :func:`njit_cached` applies the same decorator and tells mypy the kernel keeps its own
signature. The dispatcher it returns wraps the function where it is defined, so numba's cache stays keyed by the
kernel's own module, name and source file (:mod:`op2motion.processes.compiled` names its locks the same way).
"""

from __future__ import annotations

from typing import Any, Callable, TypeVar, cast

import numba

F = TypeVar("F", bound=Callable[..., Any])


def njit_cached(fn: F) -> F:
    """``numba.njit(cache=True, error_model="numpy")(fn)``: the kernel compiled at its first call and cached on disk,
    typed as ``fn`` (the dispatcher is called as the function; its own attributes, ``py_func`` and the like, are
    reached through ``getattr``)."""
    return cast(F, numba.njit(cache=True, error_model="numpy")(fn))
