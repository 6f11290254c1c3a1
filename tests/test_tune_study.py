"""Tuning studies (op2motion.tune): real Optuna studies in a real SQLite file on a known landscape: the search finds
the fast and safe corner, a study stopped by Ctrl-C resumes without losing a finished trial, trials that stop at
their first failure are told as pruned, and bad parameter ranges are refused naming the parameter."""

from __future__ import annotations

import pytest

from op2motion.errors import InputError, Interrupted
from op2motion.tune.space import Param, ParameterSpace
from op2motion.tune.study import TrialOutcome, choose, open_study, pareto, rows, run_study

SPACE = ParameterSpace((Param("step_s", 0.2, 0.5, "s"), Param("step_length_m", 0.02, 0.08, "m")))
SEED = 3


def landscape(point: dict[str, float]) -> TrialOutcome:
    """A known answer: speed = length / time; margin falls with speed; beyond 0.3 m/s the walk 'falls' at once."""
    speed = point["step_length_m"] / point["step_s"]
    if speed > 0.3:
        return TrialOutcome(speed, -1.0, False, 1, 8, "fell", 0.0)
    return TrialOutcome(speed, 1.0 - speed / 0.3, True, 8, 8, None, 0.0)


class InThread:
    """Trials run here, one at a time, optionally interrupted after ``stop_after`` of them."""

    workers = 1

    def __init__(self, stop_after: int | None = None):
        self.stop_after, self._pending, self.count = stop_after, [], 0

    def submit(self, number, fn, *args):
        self._pending.append((number, fn(*args)))

    def finished(self):
        self.count += len(self._pending)
        if self.stop_after is not None and self.count > self.stop_after:
            raise KeyboardInterrupt
        out, self._pending = self._pending, []
        return out

    @property
    def running(self):
        return len(self._pending)


@pytest.mark.slow
def test_a_study_finds_the_fast_safe_corner_and_prunes_falls(tmp_path):
    study = open_study(tmp_path / "s.db", "toy", SPACE, SEED)
    assert run_study(study, SPACE, landscape, (), 40, InThread()) == 40
    table = rows(study)
    assert len(table) == 40 and any(r.state == "PRUNED" for r in table)
    assert all(r.outcome.passed for r in pareto(table))
    best = choose(table, min_margin=0.2)
    assert best is not None and 0.2 <= best.outcome.speed <= 0.3 * 0.8 + 1e-9


@pytest.mark.slow
def test_a_stopped_study_resumes_without_losing_trials(tmp_path):
    study = open_study(tmp_path / "s.db", "toy", SPACE, SEED)
    with pytest.raises(Interrupted, match="resume"):
        run_study(study, SPACE, landscape, (), 20, InThread(stop_after=7))
    kept = [r.number for r in rows(study)]
    assert len(kept) == 7
    again = open_study(tmp_path / "s.db", "toy", SPACE, SEED)                   # a new process would do the same
    assert run_study(again, SPACE, landscape, (), 20, InThread()) == 13
    assert len(rows(again)) == 20 and set(kept) <= {r.number for r in rows(again)}


#: A program that runs four trials of the toy study in ``sys.argv[1]`` and ends as the CLI does (its exit handlers,
#: then ``os._exit``), or killed (``kill``: ``os._exit`` without them, as ``kill -9`` would).
_RUN_AND_END = """
import atexit, os, sys
sys.path.insert(0, sys.argv[3])
from test_tune_study import SPACE, SEED, InThread, landscape
from op2motion.tune.study import open_study, run_study
run_study(open_study(sys.argv[1], "toy", SPACE, SEED), SPACE, landscape, (), 4, InThread())
if sys.argv[2] == "end":
    atexit._run_exitfuncs()
os._exit(0)
"""


@pytest.mark.slow
@pytest.mark.parametrize("how", ["end", "kill"])
def test_the_study_file_is_whole_when_the_program_ends_and_read_back_after_a_kill(tmp_path, how):
    """The study's SQLite log is folded into the file when the program ends (the file alone holds every trial);
    killed, it is left beside the file and the next run reads both."""
    import subprocess
    import sys
    from pathlib import Path

    db = tmp_path / "s.db"
    done = subprocess.run([sys.executable, "-c", _RUN_AND_END, str(db), how, str(Path(__file__).parent)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    if how == "end":
        assert sorted(p.name for p in tmp_path.iterdir()) == ["s.db"]
    assert len(rows(open_study(db, "toy", SPACE, SEED))) == 4


def test_a_study_of_other_parameters_is_refused(tmp_path):
    study = open_study(tmp_path / "s.db", "toy", SPACE, SEED)
    run_study(study, SPACE, landscape, (), 2, InThread())
    other = ParameterSpace((Param("step_s", 0.2, 0.5, "s"),))
    with pytest.raises(InputError, match="use another study file"):
        open_study(tmp_path / "s.db", "toy", other, SEED)
    (tmp_path / "junk.db").write_text("not sqlite", encoding="utf-8")
    with pytest.raises(InputError, match="study"):
        open_study(tmp_path / "junk.db", "toy", SPACE, SEED)


@pytest.mark.parametrize("override, words", [
    (["nope", "1", "2"], "among"), (["step_s", "0.4", "0.3"], "low < high"), (["step_s", "0.1", "0.3"], "within"),
    (["step_s", "nan", "0.3"], "low < high"), (["step_s", "a", "0.3"], "two numbers"), (["step_s", "0.3"], "NAME"),
])
def test_bad_ranges_are_refused_naming_the_parameter(override, words):
    with pytest.raises(InputError, match=words):
        SPACE.narrowed([override])
    assert SPACE.narrowed([["step_s", "0.25", "0.3"]]).params[0].low == 0.25


def test_the_p_gain_is_searched_only_when_asked_for():
    from op2motion.tune.spaces import stock_space, walk_space

    for space in (walk_space("forward"), stock_space()):
        assert "p_gain" not in space.names
        added = space.narrowed([["p_gain", "32", "40"]])
        assert added.names[-1] == "p_gain" and (added.params[-1].low, added.params[-1].high) == (32, 40)
        with pytest.raises(InputError, match="within"):
            space.narrowed([["p_gain", "0", "40"]])
