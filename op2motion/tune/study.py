"""A tuning study: Optuna asks for points of a :class:`~.space.ParameterSpace`, the trials run on an executor
(:mod:`.executor`), each result is told back, and the study lives in a local SQLite file so that it can be stopped
and resumed without losing a trial.

* **Two objectives**, both maximised: the speed and the margin (:class:`TrialOutcome`): the fastest walk is not the
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
* **Whose study**: a study op2motion makes carries a mark (:func:`study_mark`, the study's ``op2motion`` user
  attribute): the parameters searched and what the run was for (the task, the spec's and the base settings'
  fingerprints: :func:`op2motion.tune.trial.identity`). A study is resumed only for the same (its ranges may be
  narrowed), and only a file that is op2motion's is ever opened for writing (:func:`check_study`): an empty file,
  another program's SQLite or Optuna file is looked at read-only and refused, left as it was. A new file is made
  beside its place and moved there whole, mark and all.
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
import contextlib
import functools
import json
import logging
import math
import os
import sqlite3
import stat
import time
import urllib.parse
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

from op2motion.errors import InputError, Interrupted, ref
from op2motion.fileio import check_output_path, new_file_beside
from op2motion.jsonout import JsonObject
from op2motion.tune.space import ParameterSpace

MIN_MARGIN = 0.2                # the chosen point holds everywhere with at least this share of every bound to spare
MAX_TRIALS = 10_000
STARTUP_TRIALS = 10             # random points before the sampler models the space
SCHEMA = "op2motion.study/1"    # the version of the mark op2motion writes on its studies (:func:`study_mark`)
MARK = "op2motion"              # ... and the study user attribute that holds it
UNCOMPARED = frozenset({"schema", "params", "ranges"})   # the mark's entries a resumed study may differ in (or are
                                                         # compared on their own: params)
OPTUNA_TABLES = frozenset({"studies", "study_user_attributes", "trials", "version_info"})
SQLITE_MAGIC = b"SQLite format 3\x00"       # the first 16 bytes of every SQLite database file


@dataclass(frozen=True)
class TrialOutcome:
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

    def as_dict(self) -> JsonObject:
        """JSON-ready dict."""
        return asdict(self)


@dataclass(frozen=True)
class TrialRow:
    """One finished trial: its number, point, outcome (None for one that failed to run) and state (``COMPLETE``, or
    ``PRUNED`` for one that stopped at its first failure)."""

    number: int
    params: dict[str, float]
    outcome: TrialOutcome | None
    state: str


def check_budget(trials: int) -> int:
    """A study's budget of trials: 1 to :data:`MAX_TRIALS`."""
    if isinstance(trials, bool) or not isinstance(trials, int) or not 1 <= trials <= MAX_TRIALS:
        raise InputError(f"expected 1 to {MAX_TRIALS} trials, got {trials!r}", "trials")
    return trials


def study_mark(space: ParameterSpace, about: Mapping[str, Any] | None = None) -> JsonObject:
    """The mark op2motion writes on a study it makes (the study's ``op2motion`` user attribute): the schema, the
    parameters searched and their ranges when it was made, and ``about``: what else it was made for (e.g. the
    task, the spec's fingerprint: :func:`op2motion.tune.trial.identity`; a value that is a mapping with a
    ``sha256`` is compared by that alone, its ``name`` shown)."""
    return {"schema": SCHEMA, "params": list(space.names),
            "ranges": {p.name: [p.low, p.high] for p in space.params}, **(about or {})}


def check_study(path: str | Path, name: str, space: ParameterSpace, about: Mapping[str, Any] | None = None) -> bool:
    """Refuse (:class:`InputError`, param ``study``), reading nothing but read-only, a study file that cannot be
    this run's: not a regular file, not writable, not an op2motion study file (:func:`_marks`), or holding the study
    ``name`` made for other parameters or another ``about`` (:func:`study_mark`), or one op2motion did not make.
    Returns whether the file exists (False: it will be made)."""
    target = check_output_path(path, "study")
    if not target.exists():
        return False
    found = _marks(target).get(name)
    if found is not None:
        mark, trials = found
        if mark is None and trials:
            raise InputError(f"expected a study op2motion made, got {name!r} in {target}, which carries no "
                             f"op2motion mark: use another {ref('study')} file or {ref('study_name')}", "study")
        if mark is not None:
            _same(mark, study_mark(space, about), name, target)
    return True


def open_study(path: str | Path, name: str, space: ParameterSpace, seed: int,
               about: Mapping[str, Any] | None = None) -> Any:
    """The study ``name`` in the SQLite file ``path``, made if new (a new file is made beside its place, marked,
    :func:`study_mark`, and moved there whole). The file is looked at read-only first: one that :func:`check_study`
    refuses is bad input and never opened for writing. Trials left running by a killed study are marked failed."""
    import optuna
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(logging.WARNING)
    mark = study_mark(space, about)
    target = Path(path)
    if not check_study(target, name, space, about):
        with new_file_beside(target, "study") as tmp:
            _make(tmp, name, mark)
    sampler = optuna.samplers.TPESampler(seed=seed, multivariate=True, n_startup_trials=STARTUP_TRIALS)
    storage = _storage(target)
    atexit.register(storage.engine.dispose)         # the last connection closed folds the log into the file
    study = _load(storage, name, sampler)
    recorded = study.user_attrs.get(MARK)
    if recorded is None:            # made here, its mark never written (killed in between): nothing ran in it
        if study.get_trials(deepcopy=False):
            raise InputError(f"expected a study op2motion made, got {name!r} in {target}, which carries no "
                             f"op2motion mark", "study")
        study.set_user_attr(MARK, mark)
    else:
        _same(recorded, mark, name, target)
    for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        study.tell(trial.number, state=TrialState.FAIL)
    return study


def _storage(path: Path) -> Any:
    """Optuna's storage on the SQLite file ``path`` (connections: :func:`_connect`)."""
    import optuna

    try:
        return optuna.storages.RDBStorage(f"sqlite:///{path}",
                                          engine_kwargs={"creator": functools.partial(_connect, path)})
    except Exception as exc:  # noqa: BLE001 (SQLAlchemy and Optuna raise many kinds for a file they cannot use)
        raise InputError(f"expected an Optuna study file (SQLite), got one that cannot be opened: "
                         f"{str(exc).splitlines()[0][:120]}", "study") from None


def _load(storage: Any, name: str, sampler: Any) -> Any:
    """The study ``name`` in ``storage``, made if new (two objectives, both maximised)."""
    import optuna

    try:
        return optuna.create_study(storage=storage, study_name=name, load_if_exists=True,
                                   directions=["maximize", "maximize"], sampler=sampler)
    except Exception as exc:  # noqa: BLE001 (as in _storage)
        raise InputError(f"expected an Optuna study file (SQLite), got one that cannot be opened: "
                         f"{str(exc).splitlines()[0][:120]}", "study") from None


def _make(path: Path, name: str, mark: dict[str, Any]) -> None:
    """A new study file at ``path`` (an empty temp file): Optuna's tables and the study ``name`` with its mark, the
    write-ahead log folded into the file, so that the file alone says whose it is (:func:`_marks` reads no log)."""
    import optuna

    storage = _storage(path)
    try:
        study = _load(storage, name, optuna.samplers.RandomSampler())
        study.set_user_attr(MARK, mark)
    finally:
        storage.remove_session()
        storage.engine.dispose()
    try:
        connection = sqlite3.connect(str(path))
        try:
            connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        finally:
            connection.close()                          # the last connection: the log goes
    finally:
        for side in ("-wal", "-shm", "-journal"):       # left only by a failure: not the user's files
            with contextlib.suppress(OSError):
                os.unlink(f"{path}{side}")


def _marks(path: Path) -> dict[str, tuple[dict[str, Any] | None, int]]:
    """Each study in the file ``path``: (its op2motion mark or None, its number of trials). Read-only, and without
    the write-ahead log (``immutable``: ``mode=ro`` alone makes ``-wal`` and ``-shm`` files beside a file in WAL
    mode; op2motion folds a new file's mark into it, :func:`_make`). Refused (bad input): an empty file, one that is
    not SQLite, an SQLite file without Optuna's tables, or one in which no study carries op2motion's mark."""
    def refuse(what: str) -> InputError:
        return InputError(f"expected an op2motion study file, got {what}: {path} (left as it is)", "study")

    head = _head(path)
    if not head:
        raise refuse("an empty file")
    if not head.startswith(SQLITE_MAGIC):
        raise refuse("a file that is not SQLite")
    try:
        connection = sqlite3.connect(f"file:{urllib.parse.quote(str(path.resolve()))}?mode=ro&immutable=1",
                                     uri=True)
        try:
            tables = {r[0] for r in connection.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            if not OPTUNA_TABLES <= tables:
                raise refuse("an SQLite database without Optuna's tables")
            found = connection.execute(
                "SELECT s.study_name, a.value_json, (SELECT COUNT(*) FROM trials t WHERE t.study_id = s.study_id) "
                "FROM studies s LEFT JOIN study_user_attributes a ON a.study_id = s.study_id AND a.key = ?",
                (MARK,)).fetchall()
        finally:
            connection.close()
    except sqlite3.Error as exc:
        raise refuse(f"an SQLite file that cannot be read ({exc})") from None
    marks = {study: (_parsed(value), int(trials)) for study, value, trials in found}
    if not any(mark is not None for mark, _ in marks.values()):
        raise refuse("an Optuna study file that op2motion did not make (no study in it carries op2motion's mark)")
    return marks


def _head(path: Path) -> bytes:
    """The first bytes of ``path`` (a regular file: :func:`check_output_path` said so; opened without blocking all
    the same)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        raise InputError(f"cannot read the study file: {exc.strerror or exc}", "study") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise InputError(f"expected a study file (a regular file), got something else: {path}", "study")
        return os.read(fd, len(SQLITE_MAGIC))
    finally:
        os.close(fd)


def _parsed(value: str | None) -> dict[str, Any] | None:
    """A mark from its stored JSON (None: no mark, or not one of op2motion's)."""
    try:
        mark = json.loads(value) if value is not None else None
    except ValueError:
        return None
    return mark if isinstance(mark, dict) and "schema" in mark else None


def _same(recorded: Mapping[str, Any], current: Mapping[str, Any], name: str, path: Path) -> None:
    """Refuse to resume the study ``name`` (marked ``recorded``) for ``current``, naming both, unless it was made
    with this schema, for the same of everything the mark holds (first: the spec, the task...) and the same
    parameters (their ranges may differ: a study is narrowed by resuming it with ``--param``)."""
    where = f"the study {name!r} in {path}"
    if recorded.get("schema") != SCHEMA:
        raise InputError(f"expected a study of schema {SCHEMA}, got {where} of schema {recorded.get('schema')!r} "
                         f"(made by another version of op2motion)", "study")
    for key in [*current, *(k for k in recorded if k not in current)]:
        if key in UNCOMPARED:
            continue
        if _fingerprint(recorded.get(key)) != _fingerprint(current.get(key)):
            raise InputError(f"{where} was made for {key} {_label(recorded.get(key))}; this run's {key} is "
                             f"{_label(current.get(key))}: use another {ref('study')} file or {ref('study_name')}",
                             "study")
    old, new = recorded.get("params") or [], current["params"]
    if set(old) != set(new):
        raise InputError(f"{where} searched {', '.join(sorted(old))}; this run searches {', '.join(new)}: use "
                         f"another {ref('study')} file or {ref('study_name')}", "study")


def _fingerprint(value: Any) -> Any:
    return value.get("sha256") if isinstance(value, Mapping) and "sha256" in value else value


def _label(value: Any) -> str:
    if value is None:
        return "(not recorded)"
    if isinstance(value, Mapping) and "sha256" in value:
        return f"{value.get('name', '?')} (sha256 {str(value['sha256'])[:12]})"
    return str(value)


def _connect(path: Path) -> Any:
    """A connection to the study file: write-ahead log, commits not flushed to the disk one by one (see the module
    docstring)."""
    connection = sqlite3.connect(str(path), check_same_thread=False)
    connection.execute("PRAGMA journal_mode=WAL")
    connection.execute("PRAGMA synchronous=NORMAL")
    return connection


def violation(outcome: TrialOutcome) -> float:
    """How far a trial is from holding (0: it held everywhere): the margin it lacked (at least 0.01) plus the share
    of its runs never made (a plan refused before any run: 1)."""
    if outcome.passed:
        return 0.0
    lacked = max(0.01, -outcome.margin) if math.isfinite(outcome.margin) else 1.0
    return lacked + (outcome.planned - outcome.runs) / max(outcome.planned, 1)


def _tell(study: Any, trial: Any, outcome: TrialOutcome) -> None:
    for key, value in outcome.as_dict().items():
        trial.set_user_attr(key, value)
    trial.set_user_attr("violation", violation(outcome))
    trial.set_constraint("violation", violation(outcome))     # Optuna 5: the samplers weigh feasibility by it
    margin = outcome.margin if math.isfinite(outcome.margin) else -1.0
    study.tell(trial, [outcome.speed, max(margin, -1.0)])


def run_study(study: Any, space: ParameterSpace, evaluate: Callable[..., TrialOutcome], args: tuple[Any, ...],
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
        outcome = TrialOutcome(**{k: attrs[k] for k in TrialOutcome.__dataclass_fields__}) if "speed" in attrs else None
        state = "PRUNED" if outcome is not None and outcome.pruned else t.state.name
        out.append(TrialRow(t.number, dict(t.params), outcome, state))
    return out


def _held(table: Iterable[TrialRow]) -> list[tuple[TrialRow, TrialOutcome]]:
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


def timed(fn: Callable[[], TrialOutcome]) -> TrialOutcome:
    """``fn()`` with its wall time filled in."""
    t0 = time.perf_counter()
    out = fn()
    return TrialOutcome(out.speed, out.margin, out.passed, out.runs, out.planned, out.problem,
                   round(time.perf_counter() - t0, 2))
