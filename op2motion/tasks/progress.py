"""How tasks report progress, in one place: a callback of (done, total) for one stage (:data:`Progress`), or, for a
task of several stages, a maker of one per stage (:data:`ProgressFor`, called with what and its unit); the command
line supplies bars, a program may pass none (:func:`no_progress`)."""

from __future__ import annotations

import contextlib
from typing import Any, Callable, ContextManager, Iterator

#: Progress of one stage: called with (done, total).
Progress = Callable[[float, float], None]
#: Progress of a task's stages: called with (what, unit), gives a context whose value is a :data:`Progress` or None.
ProgressFor = Callable[[str, str], ContextManager[Any]]


@contextlib.contextmanager
def no_progress(what: str, unit: str) -> Iterator[None]:
    """A :data:`ProgressFor` that reports nothing."""
    yield None
