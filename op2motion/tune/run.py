"""A whole tuning run (``op2motion tune walk|stock``): search, verify, choose, write.

1. **Search** (:func:`~.study.run_study`): Optuna asks for points; each trial (:func:`~.trial.evaluate`) walks the
   search's bodies (the nominal body, the family's four corners, the torso CoM at both ends) in both engines
   (:data:`~.trial.SEARCH_ENGINES`), stopping at the first run that does not hold; the study is kept in its SQLite
   file (stop and resume at will).
2. **Verify**: the Pareto front's points (those with at least :data:`~.study.MIN_MARGIN` to spare first), fastest
   first, each walked :data:`VERIFY_STEPS` steps on every body of the family in both engines, with
   :data:`~.walkers.VERIFY_PUSH_N` side pushes for op2motion's walk (one trial per body, on the same executor),
   until one holds everywhere (at most ``verify`` of them).
3. **Write**: that point as a preset (or a ``config.ini``), atomically, with what the study found in its header and
   a JSON beside it (:func:`result_json`): trials, pruned, wall time, workers, the verified table; and the Pareto
   figure if asked. Nothing is written when no point holds (exit 1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Callable

from op2motion.jsonout import JsonObject
from op2motion.processes.workers import ExecutorName
from op2motion.tune.study import TrialOutcome, TrialRow, pareto, rows
from op2motion.tune.trial import Task, evaluate

if TYPE_CHECKING:
    from op2motion.physics import EngineName
    from op2motion.tune.trial import Direction
    from op2motion.tune.walkers import WalkerKind

VERIFY_STEPS = 20           # the verification's walk [steps] (the acceptance's)
VERIFY_ENGINES: tuple[EngineName, ...] = ("pybullet", "mujoco")


@dataclass
class TuneResult:
    """What a tuning run found: the study's trials, the chosen point and its verified runs per member, the settings
    written (or None), the verification walk's steps and side pushes [N], and the cost (wall time [s] of this run,
    the trials' summed time [s], workers, executor)."""

    kind: WalkerKind
    direction: Direction
    table: list[TrialRow]
    chosen: TrialRow | None = None
    verified: dict[str, TrialOutcome] = field(default_factory=dict)
    rejected: list[tuple[int, str]] = field(default_factory=list)
    settings: Any = None
    wall_s: float = 0.0
    study_wall_s: float = 0.0
    workers: int = 1
    executor: ExecutorName = "process"
    ran: int = 0
    verify_steps: int = VERIFY_STEPS
    verify_push_n: float = 0.0

    @property
    def verified_speed(self) -> float | None:
        """The nominal body's measure in the verification (the slowest engine's)."""
        nominal = self.verified.get("nominal")
        return None if nominal is None else nominal.speed


def verify(point: dict[str, float], task: Task, trials: Any, on_run: Callable[[int, int], Any] | None = None,
           members: tuple[str, ...] | None = None, steps: int = VERIFY_STEPS) -> dict[str, TrialOutcome]:
    """``point`` on every member of the family (or just ``members``), both engines, ``steps`` steps (pushed for a
    walk), one trial per member on ``trials``; the outcome per member name."""
    from op2motion.physics import family
    from op2motion.tune.trial import spec_of

    names = list(members) if members is not None else [m.name for m in family(spec_of(task.spec_path))]
    push = task.walker.verify_push_n
    out: dict[str, TrialOutcome] = {}
    pending = dict(enumerate(names))
    for number, name in pending.items():
        trials.submit(number, evaluate, point, replace(task, members=(name,), engines=VERIFY_ENGINES,
                                                      steps=steps, push_n=push))
    while len(out) < len(names):
        for number, outcome in trials.finished():
            out[pending[number]] = outcome
            if on_run is not None:
                on_run(len(out), len(names))
    return {n: out[n] for n in names}


def candidates(table: list[TrialRow], limit: int) -> list[TrialRow]:
    """The points worth verifying, at most ``limit``: the Pareto front's with at least :data:`~.study.MIN_MARGIN` to
    spare, fastest first, then the rest of the front (every bound kept on the search's bodies), fastest first: the
    whole family decides."""
    from op2motion.tune.study import MIN_MARGIN

    front = [r for r in pareto(table) if r.outcome is not None and r.outcome.margin > 0.0]
    ordered = sorted(front, key=lambda r: (r.outcome.margin < MIN_MARGIN, -r.outcome.speed))  # type: ignore
    return ordered[:limit]


@dataclass(frozen=True)
class Effort:
    """How much a run does: the study's budget of ``trials``, the best points to ``verify`` at most, the bodies
    to verify on (``verify_members``; None: the whole family) and the verification walk's ``verify_steps`` (fewer
    bodies or steps for a quick look, not a tuned result)."""

    trials: int
    verify: int = 3
    verify_members: tuple[str, ...] | None = None
    verify_steps: int = VERIFY_STEPS


def search_and_verify(study: Any, space: Any, task: Task, effort: Effort, trials: Any,
                      on_trial: Callable[[int, int], Any] | None = None,
                      on_run: Callable[[int, int], Any] | None = None) -> TuneResult:
    """Steps 1 and 2 of the module docstring; the result (``settings`` set when a point held everywhere)."""
    from op2motion.tune.study import run_study
    from op2motion.tune.trial import settings

    t0 = time.perf_counter()
    ran = run_study(study, space, evaluate, (task,), effort.trials, trials, on_trial)
    table = rows(study)
    result = TuneResult(task.kind, task.direction, table, workers=trials.workers, ran=ran,
                        verify_steps=effort.verify_steps, verify_push_n=task.walker.verify_push_n)
    for row in candidates(table, effort.verify):
        runs = verify(row.params, task, trials, on_run, effort.verify_members, effort.verify_steps)
        problems = [o.problem for o in runs.values() if not o.passed]
        if problems:
            result.rejected.append((row.number, str(problems[0])))
            continue
        result.chosen, result.verified = row, runs
        result.settings = settings(replace(task, steps=effort.verify_steps), row.params)
        break
    result.wall_s = time.perf_counter() - t0
    result.study_wall_s = float(study.user_attrs.get("wall_s", 0.0)) + result.wall_s
    study.set_user_attr("wall_s", result.study_wall_s)          # the study's wall time over every run that resumed it
    return result


def result_json(result: TuneResult) -> JsonObject:
    """The run's figures for the JSON beside the written settings and ``--json``."""
    complete = [r for r in result.table if r.state == "COMPLETE"]
    pruned = [r for r in result.table if r.state == "PRUNED"]
    trial_s = sum(r.outcome.seconds for r in result.table if r.outcome is not None)
    chosen = result.chosen
    return {"kind": result.kind, "direction": result.direction,
            "trials": {"finished": len(result.table), "complete": len(complete), "pruned": len(pruned),
                       "this_run": result.ran},
            "cost": {"wall_s": round(result.wall_s, 1), "study_wall_s": round(result.study_wall_s, 1),
                     "trial_s": round(trial_s, 1), "workers": result.workers, "executor": result.executor},
            "pareto": [{"number": r.number, "speed": round(r.outcome.speed, 4), "margin": round(r.outcome.margin, 3)}
                       for r in pareto(result.table) if r.outcome is not None],
            "chosen": None if chosen is None else {"number": chosen.number, "params": chosen.params,
                                                   "search": None if chosen.outcome is None else
                                                   chosen.outcome.as_dict()},
            "rejected": [{"number": n, "problem": p} for n, p in result.rejected],
            "verified": {name: o.as_dict() for name, o in result.verified.items()},
            "verified_speed": result.verified_speed}


def header_lines(result: TuneResult, unit: str) -> list[str]:
    """What the study found, for the written file's header."""
    speed = result.verified_speed or 0.0
    worst = min((o.margin for o in result.verified.values()), default=0.0)
    pruned = sum(r.state == "PRUNED" for r in result.table)
    trial_s = sum(r.outcome.seconds for r in result.table if r.outcome is not None)
    pushes = f", {result.verify_push_n:g} N side pushes" if result.verify_push_n else ""
    return [f"Tuned by op2motion tune {result.kind} ({result.direction}): {len(result.table)} trials "
            f"({pruned} pruned), {result.study_wall_s:.0f} s wall on {result.workers} "
            f"{result.executor} worker(s) ({trial_s:.0f} s of trials; this run "
            f"{result.wall_s:.0f} s).",
            f"Verified: {result.verify_steps} steps on every body of the robustness family ({len(result.verified)}) in "
            f"PyBullet and MuJoCo (MX-28 servo model, 1 kHz){pushes}: "
            f"all hold; nominal {speed:.3f} {unit} (slowest engine), least margin {worst:.2f}.",
            "Figures: the JSON file beside this one."]
