"""One word list per choice: each Literal alias offers what the CLI flags offer; its narrowing refuses the rest."""

from __future__ import annotations

import argparse
import ast
import re
from pathlib import Path
from typing import get_args

import pytest
from helpers import source_tree

from op2motion.cli import build_parser
from op2motion.errors import InputError
from op2motion.formats.motionfile import PLANNERS, PROFILES, PlannerName, Profile
from op2motion.kinematics import MODELS, ModelName
from op2motion.physics import ENGINES, EngineName
from op2motion.processes.workers import EXECUTORS, ExecutorName
from op2motion.robot.balance import COM_MODELS, ComModel
from op2motion.robot.support import SIDES, Side, Support, SupportName, as_side
from op2motion.tune.trial import DIRECTIONS, Direction


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


#: Parameters (and dataclass fields) whose name says they hold one of the choices above.
CHOICE_NAMES = {"side", "sides", "hand", "hands", "support", "supports", "stance", "swing", "foot", "engine", "engines",
                "planner", "profile", "executor", "direction", "model", "com_model"}
#: The ones that stay ``str`` on purpose, "module:qualified name:parameter" -> why.
PLAIN_STR_ALLOWED = {
    # book.py is plain data below every layer (it imports nothing of op2motion, so it cannot name Side)
    "op2motion/book.py:Scenario:support": "the book's scenarios, below robot/sides.py",
    "op2motion/book.py:Scenario:hand": "the book's scenarios, below robot/sides.py",
    "op2motion/book.py:ArmRun:hand": "the book's printed arm-IK runs, below robot/sides.py",
    "op2motion/kinematics/arm_ik.py:Arm:hand": "the hand's point name (left_hand), not a side; Arm.side is the side",
    "op2motion/library/index.py:IndexRow:hand": "read back as written in a pose file's provenance: narrowing would "
                                                "drop files the index keeps today",
    "op2motion/motion/getup_ways.py:Ways.stock:side": "the side a robot lies on (front, back, left, right), not a Side",
    "op2motion/motion/getup_ways.py:Ways.own:side": "the side a robot lies on (front, back, left, right), not a Side",
    "op2motion/motion/getup_ways.py:Ways.way:side": "the side a robot lies on (front, back, left, right), not a Side",
    "op2motion/physics/report.py:PushResult:direction": "a push's direction (forward, backward, left, right), not "
                                                        "the tuned walk's Direction",
    "op2motion/robot/joints.py:hip_roll_sign:side": "a joint-name prefix (l, r) as well as a side word",
    "op2motion/robot/spec.py:Servo:model": "the servo's model name (MX-28), not a kinematic ModelName",
}



def _plain(annotation: ast.expr | None) -> bool:
    """The annotation holds ``str`` outside dict and Mapping keys (the dicts keyed by side stay ``dict[str, ...]``)."""
    text = "" if annotation is None else ast.unparse(annotation)
    return bool(re.search(r"\bstr\b", re.sub(r"(dict|Mapping)\[[^\]]*\]", "", text)))


def _plain_str_choices(root: Path) -> set[str]:
    """Every parameter or dataclass field under ``root``/op2motion named like a choice and annotated with ``str``,
    as "path:qualified name:parameter"."""
    found = set()
    for path in sorted((root / "op2motion").rglob("*.py")):
        where = path.relative_to(root).as_posix()

        def visit(node: ast.AST, scope: str) -> None:
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    a = child.args
                    found.update(f"{where}:{scope}{child.name}:{arg.arg}"
                                 for arg in a.posonlyargs + a.args + a.kwonlyargs
                                 if arg.arg in CHOICE_NAMES and _plain(arg.annotation))
                    visit(child, f"{scope}{child.name}.")
                elif isinstance(child, ast.ClassDef):
                    found.update(f"{where}:{scope}{child.name}:{st.target.id}" for st in child.body
                                 if isinstance(st, ast.AnnAssign) and isinstance(st.target, ast.Name)
                                 and st.target.id in CHOICE_NAMES and _plain(st.annotation))
                    visit(child, f"{scope}{child.name}.")

        visit(source_tree(path), "")
    return found


def test_no_choice_parameter_is_a_plain_str():
    """A side, hand, support, engine, planner, profile, executor, direction or model is typed with its alias (or a
    union with the Support enum), never a plain ``str``, except the few listed with their reason."""
    found = _plain_str_choices(Path(__file__).resolve().parents[1])
    assert found - set(PLAIN_STR_ALLOWED) == set(), "annotate these with their Literal alias"
    assert set(PLAIN_STR_ALLOWED) - found == set(), "stale allow-list entries: remove them"


def test_the_plain_str_scan_finds_planted_parameters(tmp_path):
    """The scan is not vacuous: plain-str choices in a function, a method and a dataclass field are caught; aliases,
    unions with the enum and dicts keyed by side are not."""
    (tmp_path / "op2motion").mkdir()
    (tmp_path / "op2motion" / "planted.py").write_text(
        "def f(side: str, hand: Side, feet: dict[str, int], supports: Sequence[str]) -> None: ...\n"
        "class C:\n"
        "    engine: str | None\n"
        "    support: Support | SupportName\n"
        "    def m(self, planner: str = 'rrt', corners: Mapping[str, int] = {}) -> None: ...\n", encoding="utf-8")
    assert _plain_str_choices(tmp_path) == {"op2motion/planted.py:f:side", "op2motion/planted.py:f:supports",
                                            "op2motion/planted.py:C:engine", "op2motion/planted.py:C.m:planner"}
