"""A quick start: importing op2motion and asking for help load none of the heavy libraries (each is loaded where it
is first used)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("pybullet", "mujoco", "pinocchio", "matplotlib", "numba", "pyswarms", "scipy", "ray", "ompl")
PROBE = """
import json, runpy, sys
sys.argv = {argv!r}
try:
    {run}
except SystemExit:
    pass
print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}})))
"""


@pytest.mark.parametrize("argv, run", [
    (["python"], "import op2motion"),
    (["op2motion", "--help"], "runpy.run_module('op2motion', run_name='__main__')"),
    (["op2motion", "optimize", "--help"], "runpy.run_module('op2motion', run_name='__main__')"),
    (["op2motion", "walk", "--help"], "runpy.run_module('op2motion', run_name='__main__')"),
], ids=["import", "help", "optimize-help", "walk-help"])
def test_no_heavy_library_is_loaded(argv, run):
    done = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, run=run)], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    loaded = set(json.loads(done.stdout.splitlines()[-1]))
    assert loaded.isdisjoint(HEAVY), sorted(loaded & set(HEAVY))


def _loaded(argv: list[str], run: str = "runpy.run_module('op2motion', run_name='__main__')") -> set[str]:
    """Every module (full dotted names) loaded by ``op2motion ARGV`` run in a fresh interpreter (by ``run``)."""
    done = subprocess.run([sys.executable, "-c", PROBE.format(argv=["op2motion", *argv], run=run)
                           .replace("m.split('.')[0]", "m")], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.splitlines()[-1]))


def test_help_loads_no_numpy_and_no_command_module():
    """``op2motion --help`` lists every command from cli.COMMANDS: none of their modules (nor NumPy) is loaded."""
    loaded = _loaded(["--help"])
    assert "numpy" not in loaded
    assert {m for m in loaded if m.startswith("op2motion.commands.")} == {"op2motion.commands.common"}


def test_a_command_loads_its_own_command_module_only():
    loaded = _loaded(["optimize", "--help"])
    commands = {m.removeprefix("op2motion.commands.") for m in loaded if m.startswith("op2motion.commands.")}
    assert commands == {"common", "posture"}, commands


def test_the_command_table_is_what_the_command_modules_register():
    """cli.COMMANDS (what ``--help`` lists without loading the modules) names each command in the order, with the
    help line and in the module, that the modules themselves register."""
    import importlib

    from op2motion.cli import COMMANDS, _top_parser
    from op2motion.commands.common import Parser

    registered = []
    for module in dict.fromkeys(module for module, _, _ in COMMANDS):
        _, sub = _top_parser(Parser)
        importlib.import_module(f"op2motion.commands.{module}").register(sub)
        registered += [(module, choice.dest, choice.help) for choice in sub._choices_actions]
    assert registered == list(COMMANDS)


def _help_texts(parser) -> dict[str, str]:
    """Every (sub)command's help text by its path, e.g. ``library build``."""
    import argparse

    texts = {"": parser.format_help()}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                texts.update({f"{name} {path}".strip(): text for path, text in _help_texts(sub).items()})
    return texts


def test_the_lazy_parser_is_the_full_parser(monkeypatch):
    """The parser the program uses (each command registered on first use) shows and parses what the full one
    does: the same help for every command and subcommand, the same arguments parsed."""
    from op2motion.cli import build_parser

    monkeypatch.setenv("COLUMNS", "120")
    lazy, full = build_parser(lazy=True), build_parser()
    assert _help_texts(lazy) == _help_texts(full)
    argv = ["optimize", "--target", "0.1", "0.05", "0.07", "--seed", "3", "--json"]
    parsed, expected = vars(build_parser(lazy=True).parse_args(argv)), vars(full.parse_args(argv))
    assert {k: v for k, v in parsed.items() if k != "parser"} == {k: v for k, v in expected.items() if k != "parser"}


@pytest.mark.slow
def test_the_main_job_loads_no_scipy_linalg_spatial_or_optimize_and_no_pyswarms_package(tmp_path):
    """``optimize`` (a short search, no refinement) runs pyswarms' GlobalBestPSO and the compiled cost without
    SciPy's linalg, spatial or optimize packages and leaves no ``pyswarms`` module loaded (processes/imports.py)."""
    loaded = _loaded(["optimize", "--iters", "3", "--particles", "4", "--restarts", "0", "--no-refine", "--out",
                      str(tmp_path / "pose.json")], run="from op2motion.cli import main; main()")   # not os._exit
    assert "numba" in loaded and "op2motion.posture.kernel" in loaded         # the compiled cost ran
    assert not {"scipy.linalg", "scipy.spatial", "scipy.optimize", "matplotlib"} & loaded
    assert not [m for m in loaded if m.startswith("pyswarms")]
