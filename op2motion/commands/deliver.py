"""The delivery of a task's result on the command line (:func:`deliver`): the files written when it is a yes, the
report printed (``--json``: the result's ``as_dict()``), warnings on stderr, exit 1 with the phrase when it is a no
(130 when the no is a stop the user asked for).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any, Literal

from op2motion.commands.common import emit, warn
from op2motion.errors import CheckFailed, Interrupted

if TYPE_CHECKING:
    from op2motion.fileio import OutputSet
    from op2motion.tasks.result import TaskResult


def deliver(args: argparse.Namespace, result: TaskResult[Any], outputs: OutputSet | None = None,
            written_as: Literal["each", "one", "none"] = "each", lines_shown: bool = False) -> int:
    """Write a yes's files (atomically, together, into ``outputs``: the command's output paths, checked before the
    task ran; None: the result's own), print the report (``--json``: :meth:`~.TaskResult.as_dict`; the files written
    named ``written_as`` a line each, in one line, or not at all; ``lines_shown``: the result's lines were printed
    already, while its files were being made), and turn a no into exit 1 with its phrase (nothing written); a task
    refused before its checks prints nothing."""
    from op2motion.fileio import OutputSet

    if not result.checked:
        raise CheckFailed(str(result.problem))
    if outputs is None:
        outputs = OutputSet({role: out.path for role, out in result.outputs.items()})
    for role, out in result.outputs.items():
        outputs.put(role, out.content)
    written = outputs.commit() if result.ok else {}
    files = {k: str(v) for k, v in written.items()}
    report = result.as_dict(files)
    if result.warnings is not None:
        warn(args, report, list(result.warnings))
    said = {"each": [f"  wrote {p}" for p in written.values()],
            "one": [f"  wrote {', '.join(str(p) for p in written.values())}"] if written else [],
            "none": []}[written_as]
    emit(args, report, "\n".join([*(() if lines_shown and not args.json else result.lines), *said]))
    if not result.ok:
        raise (Interrupted if result.interrupted else CheckFailed)(str(result.problem))
    return 0
