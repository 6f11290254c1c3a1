"""The library task (``library build``): a grid of reach targets solved in worker processes or on Ray, each with
the reach workflow (and its physics check), resumable; returns a :class:`~.result.TaskResult` whose figures are the
build's summary (a target not reached is recorded in the index, not a "no": the build did its job).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

from op2motion.robot.spec import Spec
from op2motion.tasks.result import TaskResult

if TYPE_CHECKING:
    from op2motion.library.build import BuildSettings, BuildSummary, Executor


@dataclass(frozen=True)
class LibraryBuild:
    """A build: the ``jobs`` (one per target), the ``settings`` of each solve, the library folder ``out``, the
    ``workers`` (0: one per core) on ``executor``, and the spec file the workers read (``spec_path``; None: the
    shipped one)."""

    jobs: list[Any]
    settings: BuildSettings
    out: str
    executor: Executor
    workers: int = 0
    spec_path: str | None = None


def build(request: LibraryBuild, spec: Spec, on_done: Callable[[Any], Any] | None = None) -> TaskResult[BuildSummary]:
    """``library build``: see the module docstring; ``on_done`` is told of each target as it finishes."""
    from op2motion.library.build import build_library

    summary = build_library(request.jobs, spec, request.out, request.settings, request.workers, request.spec_path,
                            on_done=on_done, executor=request.executor)
    text = (f"{summary.targets} targets: {summary.solved} reached, {summary.failed} not, {summary.skipped} already "
            f"done; {summary.seconds:.1f} s; index {summary.index}")
    if summary.robust_checked:
        text += (f"; on the robustness family {summary.robust_checked - summary.robust_failed} of "
                 f"{summary.robust_checked} poses stood in every run")
    return TaskResult(True, data=summary.as_dict(), lines=(text,), value=summary)
