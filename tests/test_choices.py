"""One word list per choice: each Literal alias offers what the CLI flags offer; its narrowing refuses the rest."""

from __future__ import annotations

import argparse
from typing import get_args

import pytest

from op2motion.cli import build_parser
from op2motion.errors import InputError
from op2motion.formats.motionfile import PLANNERS, PROFILES, PlannerName, Profile
from op2motion.kinematics import MODELS, ModelName
from op2motion.physics import ENGINES, EngineName
from op2motion.robot.balance import COM_MODELS, ComModel
from op2motion.robot.support import SIDES, Side, Support, SupportName, as_side
from op2motion.tune.trial import DIRECTIONS, Direction
from op2motion.workers import EXECUTORS, ExecutorName


def _choices(flag: str) -> list[tuple[str, set]]:
    """(subcommand path, choices) of every ``flag`` in the CLI's parser tree that offers choices."""
    found = []

    def walk(parser: argparse.ArgumentParser, path: str) -> None:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, f"{path} {name}".strip())
            elif flag in action.option_strings and action.choices is not None:
                found.append((path, set(action.choices)))

    walk(build_parser(), "")
    return found


#: flag -> (the alias's values, the extra words a flag may add, e.g. "both" engines or models)
FLAGS = {
    "--support": (set(get_args(SupportName)), set()),
    "--hand": (set(get_args(Side)), set()),
    "--hands": (set(get_args(Side)), set()),
    "--supports": (set(get_args(Side)), set()),
    "--engine": (set(get_args(EngineName)), {"both"}),
    "--model": (set(get_args(ModelName)), {"both"}),
    "--com-model": (set(get_args(ComModel)), set()),
    "--profile": (set(get_args(Profile)), set()),
    "--planner": (set(get_args(PlannerName)), set()),
    "--executor": (set(get_args(ExecutorName)), set()),
    "--direction": (set(get_args(Direction)), set()),
}


@pytest.mark.parametrize("flag", sorted(FLAGS))
def test_each_flag_offers_its_alias_values(flag):
    values, extra = FLAGS[flag]
    found = _choices(flag)
    assert found, f"no {flag} with choices in the CLI"
    for path, choices in found:
        assert choices - extra <= values, (path, flag, choices)
        if flag == "--support":     # a one-foot command offers the sides, a two-feet one all supports
            assert choices in (values, set(get_args(Side))), (path, choices)
        else:
            assert choices - extra == values, (path, flag, choices)


def test_the_runtime_tuples_are_the_aliases():
    assert SIDES == get_args(Side) and ENGINES == get_args(EngineName) and MODELS == get_args(ModelName)
    assert COM_MODELS == get_args(ComModel) and PROFILES == get_args(Profile) and PLANNERS == get_args(PlannerName)
    assert EXECUTORS == get_args(ExecutorName) and tuple(DIRECTIONS) == get_args(Direction)
    assert tuple(s.value for s in Support) == get_args(SupportName)


def test_as_side_narrows_and_refuses_naming_the_parameter():
    assert as_side("left", "hand") == "left" and as_side(Support.RIGHT, "support") == "right"
    for bad in ("double", "Left", None, 1):
        with pytest.raises(InputError) as err:
            as_side(bad, "hand")
        assert err.value.param == "hand" and repr(bad) in err.value.message


def test_support_narrowing_refuses_naming_the_parameter():
    with pytest.raises(InputError) as err:
        Support.of("both", "start_support")
    assert err.value.param == "start_support" and "'both'" in err.value.message
    with pytest.raises(InputError) as err:
        Support.single("double", "support")
    assert err.value.param == "support" and "expected 'left' or 'right'" in err.value.message
