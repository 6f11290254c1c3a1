"""The tuning tasks (``tune walk``, ``tune stock``): an Optuna study searched, its best points verified on the whole
family, the first that holds everywhere written as a preset (or a ``config.ini``) with the study's figures beside it
and, when asked, the Pareto figure. No point that holds is a "no" with its phrase (nothing written; more trials
resume the study).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from op2motion.jsonout import JsonObject, json_object
from op2motion.tasks.progress import ProgressFor, no_progress
from op2motion.tasks.result import Output, TaskResult

if TYPE_CHECKING:
    from op2motion.processes.workers import ExecutorName
    from op2motion.tune.run import TuneResult
    from op2motion.tune.space import ParameterSpace
    from op2motion.tune.trial import Task


@dataclass(frozen=True)
class TuneRequest:
    """A tuning run: the ``task`` (what is tuned, on which robot), its search ``space``, the study's budget of
    ``trials`` and the best points to ``verify`` at most; the study in ``study_path`` under ``study_name``, sampled
    with ``seed``; trials on ``executor`` (``process`` or ``ray``, at ``address``) with ``workers``; the outputs:
    the settings at ``out``, the figures at ``out_json``, the Pareto figure at ``plot`` (None: none)."""

    task: Task
    space: ParameterSpace
    trials: int
    verify: int
    study_path: str
    study_name: str
    out: str
    out_json: str
    seed: int = 0
    executor: ExecutorName = "process"
    workers: int = 1
    address: str | None = None
    plot: str | None = None


def check_request(request: TuneRequest) -> None:
    """Everything the run needs, checked before any file is made or opened for writing, so that a run refused at
    its start leaves the folder as it was: the outputs (each writable, none of them the study file), the budget,
    the executor (:func:`~op2motion.tune.executor.check_executor`: the address a running Ray head, Ray installed)
    and the study file (:func:`~op2motion.tune.study.check_study`: absent, or an op2motion study that this task,
    spec and parameter set may resume; looked at read-only)."""
    from op2motion.errors import OutputError, ref
    from op2motion.fileio import check_output_path
    from op2motion.tune.executor import check_executor
    from op2motion.tune.study import check_budget, check_study
    from op2motion.tune.trial import identity

    study = Path(request.study_path).resolve()
    outputs = {"out": (request.out, ref("out")), "out_json": (request.out_json, f"the JSON beside {ref('out')}"),
               "plot": (request.plot, ref("plot"))}
    for role, (path, what) in outputs.items():
        if path is not None and check_output_path(path, role).resolve() == study:
            raise OutputError(f"expected a study file other than an output ({what}), got {request.study_path}",
                              "study")
    check_budget(request.trials)
    check_study(request.study_path, request.study_name, request.space, identity(request.task))
    check_executor(request.executor, request.address)


def _search(request: TuneRequest, progress: ProgressFor) -> TuneResult:
    """Check the request, start the executor, then open (or make, or resume) the study, search, verify."""
    from op2motion.tune.executor import trials_on
    from op2motion.tune.run import Effort, search_and_verify
    from op2motion.tune.study import open_study
    from op2motion.tune.trial import identity

    check_request(request)
    with trials_on(request.executor, request.workers, request.address) as trials:   # Ray refused: no study made
        study = open_study(request.study_path, request.study_name, request.space, request.seed,
                           identity(request.task))
        with progress("trials", "trial") as on_trial, progress("verify", "body") as on_run:
            result = search_and_verify(study, request.space, request.task, Effort(request.trials, request.verify),
                                       trials, on_trial, on_run)
    result.executor = request.executor
    return result


def _settings_text(request: TuneRequest, result: TuneResult, unit: str) -> str:
    """The chosen point as a preset (``walk``, named after its file) or a ``config.ini`` (``stock``)."""
    from op2motion.tune.run import header_lines

    return request.task.walker.settings_text(result.settings, Path(request.out).stem, header_lines(result, unit))


def tune(request: TuneRequest, progress: ProgressFor | None = None) -> TaskResult[TuneResult]:
    """``tune walk|stock``: see the module docstring; ``progress`` gives the trials' and the verification's."""
    from op2motion.figures.tune import render_pareto
    from op2motion.tune.run import result_json
    from op2motion.tune.study import MIN_MARGIN, pareto

    unit = "rad/s" if request.task.direction == "turn" else "m/s"
    result = _search(request, progress or no_progress)
    data: JsonObject = {**result_json(result), "study": request.study_path}
    outputs = {}
    if request.plot:
        outputs["plot"] = Output(request.plot, render_pareto(result, pareto(result.table), MIN_MARGIN, unit))
    pruned = sum(r.state == "PRUNED" for r in result.table)
    lines = [f"tune {result.kind} {result.direction}: {len(result.table)} trials "
             f"({pruned} pruned, {result.ran} this run), {result.study_wall_s:.0f} s on "
             f"{result.workers} {result.executor} worker(s)"]
    lines += [f"  rejected in verification: trial {n}: {p}" for n, p in result.rejected]
    if result.settings is None or result.chosen is None:
        return TaskResult(False, f"no point held on every body of the family in both engines (verified "
                                 f"{len(result.rejected)}); nothing written: more --trials resume the study",
                          None, outputs, {**data, "files": {}}, tuple(lines), value=result)
    outputs["out"] = Output(request.out, _settings_text(request, result, unit))
    outputs["out_json"] = Output(request.out_json, json.dumps(json_object(data), indent=2) + "\n")
    paths = ", ".join(o.path for o in outputs.values())
    lines.append(f"  chosen trial {result.chosen.number}: nominal {result.verified_speed:.3f} {unit} in both "
                 f"engines, every body held; wrote {paths}")
    return TaskResult(True, None, None, outputs, {**data, "files": {}}, tuple(lines), value=result)
