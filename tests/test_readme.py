"""The README keeps its promises: every example line runs as written in a fresh copy of the repository, and every
command-line option has help text."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import pytest

from helpers import ROOT
from op2motion.cli import build_parser

README = (ROOT / "README.md").read_text(encoding="utf-8")


def _example_lines() -> list[str]:
    section = README.split("### Examples", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```bash\n(.*?)```", section, re.S)
    return [line for block in blocks for line in block.splitlines() if line.startswith("op2motion ")]


SKIP_DIRS = {".git", ".venv", "__pycache__", ".pytest_cache", ".hypothesis", ".ruff_cache", "build", "dist"}


def _repository_files() -> list[str]:
    """The tracked files (git), or, in a copy without git (CI), every file outside build and cache folders."""
    done = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True)
    if done.returncode == 0 and done.stdout:
        return [name.decode() for name in done.stdout.split(b"\0") if name]
    return [str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if p.is_file()
            and not SKIP_DIRS & set(p.relative_to(ROOT).parts) and not any(part.endswith(".egg-info")
                                                                           for part in p.parts)]


@pytest.fixture(scope="module")
def clone(tmp_path_factory):
    """The repository's files copied as a fresh clone would have them."""
    dest = tmp_path_factory.mktemp("clone")
    for name in _repository_files():
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes((ROOT / name).read_bytes())
    return dest


def test_the_readme_has_examples_for_every_command():
    commands = {line.split()[1] for line in _example_lines()}
    assert {"fk", "convert", "plot", "arm-ik", "optimize", "validate", "import-action", "export", "urdf",
            "library"} <= commands


@pytest.mark.parametrize("line", _example_lines(), ids=lambda line: " ".join(line.split()[:3]))
def test_readme_example_runs_as_written(clone, line):
    argv = shlex.split(line)
    done = subprocess.run([sys.executable, "-m", "op2motion", *argv[1:]], cwd=clone, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    for flag in ("-o", "--out", "--plot", "--gui-png"):        # the files it promised exist
        if flag in argv:
            assert (clone / argv[argv.index(flag) + 1]).exists(), flag


def _subparsers(parser):
    for action in parser._actions:
        if hasattr(action, "choices") and isinstance(action.choices, dict):
            for name, sub in action.choices.items():
                yield name, sub
                yield from _subparsers(sub)


def test_every_option_has_help_and_every_command_a_description():
    for name, sub in [("op2motion", build_parser()), *_subparsers(build_parser())]:
        assert sub.description, name
        for action in sub._actions:
            if action.option_strings or action.dest not in ("func", "parser"):
                assert action.help, f"{name} {action.option_strings or action.dest}"


@pytest.mark.parametrize("argv", [["library"], ["validate"], ["import-action"], ["arm-ik"], ["export"]])
def test_usage_errors_name_flags_and_placeholders_not_internal_identifiers(capsys, argv):
    from helpers import run_cli

    code, _, err = run_cli(capsys, *argv)
    assert code == 2 and err.count("\n") == 1
    assert not re.search(r"\b[a-z]+_[a-z_]+\b", err.split("error: ", 1)[1].replace("import-action", "")), err


def test_the_python_api_example_runs(clone):
    section = README.split("## Python API", 1)[1].split("\n## ", 1)[0]
    code = re.findall(r"```python\n(.*?)```", section, re.S)[0]
    done = subprocess.run([sys.executable, "-c", code], cwd=clone, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "True stands" in done.stdout and "True reached" in done.stdout
