"""``op2motion tune``: real Optuna studies of real walks in real physics, at small sizes (a few trials, the nominal
body, short walks); the full-size figures are in the README. Bad input is refused before any work."""

from __future__ import annotations

import pytest
from helpers import run_cli

from op2motion.gait.params import params_from_mapping, preset_text
from op2motion.gait.stock_config import StockConfig, parse_stock_config, stock_config_text
from op2motion.robot.specfile import tomllib
from op2motion.tune.executor import ProcessTrials
from op2motion.tune.run import VERIFY_STEPS, Effort, search_and_verify
from op2motion.tune.space import Param, ParameterSpace
from op2motion.tune.study import open_study, rows
from op2motion.tune.trial import Task, evaluate
from op2motion.tune.walkers import PresetWalker, StockWalker

SEED = 1
TRIALS = 3
STEPS = 6                       # a short walk for the search [steps]
QUICK_VERIFY_STEPS = 8          # ... and for the verification (the command verifies VERIFY_STEPS)
NOMINAL = ("nominal",)


@pytest.mark.parametrize("argv, message", [
    (("--param", "nope", "0", "1"), "expected a parameter among"),
    (("--param", "step_s", "0.4", "0.3"), "expected a range low < high"),
    (("--param", "step_s", "0.1", "0.3"), "expected a range within 0.2 to 2"),
    (("--only", "nope"), "expected parameters among"),
    (("--trials", "0"), "--trials"),
    (("--address", "127.0.0.1:1"), "--address only with --executor ray"),
])
def test_bad_input_is_refused_and_nothing_is_written(tmp_path, capsys, argv, message):
    out = tmp_path / "fast.toml"
    code, _, err = run_cli(capsys, "tune", "walk", "--out", str(out), *argv)
    assert code == 2 and message in err and err.count("\n") == 1
    assert not out.exists() and not (tmp_path / "fast.toml.study.db").exists()


@pytest.mark.physics
def test_a_walk_study_finds_verifies_and_writes_a_preset_that_reads_back(tmp_path):
    from op2motion.gait import load_preset

    space = ParameterSpace((Param("step_length_m", 0.07, 0.085, "m"),))
    task = Task(PresetWalker(load_preset("forward")), "forward", members=NOMINAL, steps=STEPS, engines=("mujoco",))
    study = open_study(tmp_path / "s.db", "walk", space, SEED)
    trials = ProcessTrials(1)                 # a worker process (each one imports the package and both engines)
    try:
        result = search_and_verify(study, space, task, Effort(TRIALS, 1, NOMINAL, QUICK_VERIFY_STEPS), trials)
    finally:
        trials.close()
    assert len(rows(study)) == TRIALS and all(r.outcome is not None for r in result.table)
    assert result.chosen is not None and result.verified["nominal"].passed, result.rejected
    params = result.settings
    assert 0.07 <= params.step_length_m <= 0.085 and params.steps == QUICK_VERIFY_STEPS != VERIFY_STEPS
    assert {o.runs for o in result.verified.values()} == {2}                 # verified in both engines
    again = params_from_mapping(tomllib.loads(preset_text(params, ["a header"])))
    assert again == params                                                   # what is written reads back the same


@pytest.mark.physics
def test_a_stock_trial_walks_the_stock_module_and_a_bad_plan_is_pruned():
    task = Task(StockWalker(StockConfig(x_move_amplitude_mm=30.0)), "forward", members=NOMINAL, steps=STEPS)
    outcome = evaluate({"period_time_ms": 600.0}, task)
    assert outcome.speed > 0.15 and not outcome.pruned                         # the stock walk at X 30 mm walks,
    assert outcome.runs == outcome.planned == len(task.engines)                 # ... in both engines,
    assert outcome.passed or "fell" not in (outcome.problem or "")              # ... judged by the walk's bounds
    walk = Task(PresetWalker(task_base()), "forward", members=NOMINAL, steps=STEPS)
    refused = evaluate({"step_length_m": 0.12, "step_s": 0.2, "max_speed_share": 0.85}, walk)
    assert refused.pruned and "plan refused" in (refused.problem or "")     # past the servos' speed: no physics run
    config = parse_stock_config(stock_config_text(StockConfig(x_move_amplitude_mm=33.0)))
    assert config.x_move_amplitude_mm == 33.0


def task_base():
    from op2motion.gait import load_preset

    return load_preset("forward")
