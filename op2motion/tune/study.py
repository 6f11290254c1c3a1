"""A tuning study: Optuna asks for points of a :class:`~.space.SearchSpace`, the trials run on an executor
(:mod:`.executor`), each result is told back, and the study lives in a local SQLite file so that it can be stopped
and resumed without losing a trial.

* **Two objectives**, both maximised: the speed and the margin (:class:`Outcome`): the fastest walk is not the
  answer if it barely holds. The chosen point (:func:`choose`) is the fastest trial that held everywhere with at
  least :data:`MIN_MARGIN` to spare; the Pareto front is drawn beside it.
* **Pruning**: Optuna's ``report``/``should_prune`` do not work in multi-objective studies, so a trial stops itself
  at its first failure (a fall on one body, say: the rest would not change the verdict): it is listed as pruned
  (:attr:`TrialRow.state`, where it stopped in its attributes). It is told to Optuna as complete with what it
  measured and a constraint violation (:func:`violation`, ``Trial.set_constraint``), so the sampler learns
  where walks fail: a pruned trial without values would count for TPE as a good one while few trials complete.
* **Resuming**: the study's name and SQLite file identify it; running the same command again continues it up to its
  budget of trials (completed and pruned ones count). Trials that were running when a study was killed are marked
  failed and asked again. Ctrl-C or SIGTERM: the running trials are marked failed, every finished one is kept, and
  :class:`~op2motion.errors.Interrupted` says how to resume.
* **The file** is SQLite in write-ahead-log mode with ``synchronous=NORMAL``: a commit is safe against the program
  being killed (Ctrl-C, SIGTERM, ``kill -9``), not against the machine losing power in that instant, and it no longer
  waits for the disk (about 20 commits a trial: with a flush each, a toy study spent three quarters of its time
  there). While a study runs, ``NAME.db-wal`` lies beside it, folded back in when the program ends (a killed one leaves
  it: keep the two together; the next run reads both).
* **Seeds**: the sampler (TPE, multivariate) is seeded; with several workers the order in which trials finish, and
  so what the sampler has seen when it asks, depends on timing.
"""

from __future__ import annotations

import atexit
import functools
import logging
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from op2motion.errors import InputError, Interrupted
from op2motion.tune.space import SearchSpace

MIN_MARGIN = 0.2                # the chosen point holds everywhere with at least this share of every bound to spare
MAX_TRIALS = 10_000
STARTUP_TRIALS = 10             # random points before the sampler models the space


@dataclass(frozen=True)
class Outcome:
    """What one trial measured: the speed [m/s] (or [rad/s] turning) that counts (the nominal body's, the slowest
    engine's), the margin (the worst run's smallest share of a bound left: 1 is perfect, 0 on a bound, below 0
    beyond it), whether every run held, how many runs were made before it stopped (``runs`` of ``planned``), why
    it failed (one phrase, or None) and its wall time [s]."""

    speed: float
    margin: float
    passed: bool
    runs: int
    planned: int
    problem: str | None
    seconds: float

    @property
    def pruned(self) -> bool:
        """Stopped before every run was made (a failure decided the verdict)."""
        return self.runs < self.planned

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


@dataclass(frozen=True)
class TrialRow:
    """One finished trial: its number, point, outcome (None for one that failed to run) and state (``COMPLETE``, or
    ``PRUNED`` for one that stopped at its first failure)."""

    number: int
    params: dict[str, float]
    outcome: Outcome | None
    state: str


def check_budget(trials: int) -> int:
    """A study's budget of trials: 1 to :data:`MAX_TRIALS`."""
    if isinstance(trials, bool) or not isinstance(trials, int) or not 1 <= trials <= MAX_TRIALS:
        raise InputError(f"expected 1 to {MAX_TRIALS} trials, got {trials!r}", "trials")
    return trials


def open_study(path: str | Path, name: str, space: SearchSpace, seed: int) -> Any:
    """The study ``name`` in the SQLite file ``path`` (created if new); a study of the same name that searched
    other parameters is bad input. Trials left running by a killed study are marked failed."""
    import optuna
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(logging.WARNING)
    sampler = optuna.samplers.TPESampler(seed=seed, multivariate=True, n_startup_trials=STARTUP_TRIALS)
    target = Path(path)
    if target.exists() and not target.is_file():
        raise InputError(f"expected a study file (SQLite), got a folder: {target}", "study")
    try:
        storage = optuna.storages.RDBStorage(f"sqlite:///{target}",
                                             engine_kwargs={"creator": functools.partial(_connect, target)})
        atexit.register(storage.engine.dispose)         # the last connection closed folds the log into the file
        study = optuna.create_study(storage=storage, study_name=name, load_if_exists=True,
                                    directions=["maximize", "maximize"], sampler=sampler)
    except Exception as exc:  # noqa: BLE001 (SQLAlchemy and Optuna raise many kinds for a file that is not a study)
        raise InputError(f"expected an Optuna study file (SQLite), got one that cannot be opened: "
                         f"{str(exc).splitlines()[0][:120]}", "study") from None
    searched = {key for t in study.get_trials(deepcopy=False) for key in t.params}
    if searched and searched != set(space.names):
        raise InputError(f"the study {name!r} in {target} searched {', '.join(sorted(searched))}; this run searches "
                         f"{', '.join(space.names)}: use another --study file or name", "study")
    for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        study.tell(trial.number, state=TrialState.FAIL)
    return study


def _connect(path: Path) -> Any:
    """A connection to the study file: write-ahead log, commits not flushed to the disk one by one (see the module
    docstring)."""
    import sqlite3

    connection = sqlite3.connect(str(path), check_same_thread=False)
    connection.execute("PRAGMA journal_mode=WAL")
    connection.execute("PRAGMA synchronous=NORMAL")
    return connection


def violation(outcome: Outcome) -> float:
    """How far a trial is from holding (0: it held everywhere): the margin it lacked (at least 0.01) plus the share
    of its runs never made (a plan refused before any run: 1)."""
    if outcome.passed:
        return 0.0
    lacked = max(0.01, -outcome.margin) if math.isfinite(outcome.margin) else 1.0
    return lacked + (outcome.planned - outcome.runs) / max(outcome.planned, 1)


def _tell(study: Any, trial: Any, outcome: Outcome) -> None:
    for key, value in outcome.as_dict().items():
        trial.set_user_attr(key, value)
    trial.set_user_attr("violation", violation(outcome))
    trial.set_constraint("violation", violation(outcome))     # Optuna 5: the samplers weigh feasibility by it
    margin = outcome.margin if math.isfinite(outcome.margin) else -1.0
    study.tell(trial, [outcome.speed, max(margin, -1.0)])


def run_study(study: Any, space: SearchSpace, evaluate: Callable[..., Outcome], args: tuple[Any, ...],
              budget: int, trials: Any, on_trial: Callable[[int, int], Any] | None = None) -> int:
    """Run ``evaluate(point, *args)`` for new points until the study holds ``budget`` finished trials, ``trials``
    (an executor) running several at a time; ``on_trial(finished, budget)`` after each. Returns the trials this run
    finished. Raises :class:`Interrupted` on Ctrl-C or SIGTERM (the finished trials are kept)."""
    from optuna.trial import TrialState

    finished_states = (TrialState.COMPLETE, TrialState.PRUNED)
    done = len(study.get_trials(deepcopy=False, states=finished_states))
    asked: dict[int, Any] = {}
    ran = 0
    try:
        while done + len(asked) < budget or asked:
            while done + len(asked) < budget and trials.running < trials.workers:
                trial = study.ask()
                asked[trial.number] = trial
                trials.submit(trial.number, evaluate, space.sample(trial), *args)
            for number, outcome in trials.finished():
                _tell(study, asked.pop(number), outcome)
                done, ran = done + 1, ran + 1
                if on_trial is not None:
                    on_trial(done, budget)
    except KeyboardInterrupt:
        for trial in asked.values():
            study.tell(trial, state=TrialState.FAIL)
        raise Interrupted(f"tuning stopped after {done} finished trial(s) of {budget}; run the same command again to "
                          "resume") from None
    return ran


def rows(study: Any) -> list[TrialRow]:
    """Every finished trial of the study (completed and pruned), in order."""
    out = []
    for t in study.get_trials(deepcopy=False):
        if t.state.name not in ("COMPLETE", "PRUNED"):
            continue
        attrs = t.user_attrs
        outcome = Outcome(**{k: attrs[k] for k in Outcome.__dataclass_fields__}) if "speed" in attrs else None
        state = "PRUNED" if outcome is not None and outcome.pruned else t.state.name
        out.append(TrialRow(t.number, dict(t.params), outcome, state))
    return out


def _held(table: Iterable[TrialRow]) -> list[tuple[TrialRow, Outcome]]:
    return [(r, r.outcome) for r in table if r.outcome is not None and r.outcome.passed and not r.outcome.pruned]


def pareto(table: Iterable[TrialRow]) -> list[TrialRow]:
    """The trials that held everywhere and that no other such trial beats in both speed and margin."""
    held = _held(table)
    return [r for r, o in held if not any(p.speed >= o.speed and p.margin >= o.margin
                                          and (p.speed, p.margin) != (o.speed, o.margin) for _, p in held)]


def choose(table: Iterable[TrialRow], min_margin: float = MIN_MARGIN) -> TrialRow | None:
    """The fastest trial that held everywhere with at least ``min_margin`` to spare (None: none did)."""
    table = list(table)
    front = {r.number for r in pareto(table)}
    good = [(r, o) for r, o in _held(table) if r.number in front and o.margin >= min_margin]
    return max(good, key=lambda ro: ro[1].speed)[0] if good else None


def timed(fn: Callable[[], Outcome]) -> Outcome:
    """``fn()`` with its wall time filled in."""
    t0 = time.perf_counter()
    out = fn()
    return Outcome(out.speed, out.margin, out.passed, out.runs, out.planned, out.problem,
                   round(time.perf_counter() - t0, 2))
