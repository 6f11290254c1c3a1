"""The README and the pages under docs/ keep their promises: every example line runs as written in a fresh copy of
the repository, the Python examples run, the tables are what the code gives today, and every command-line option
has help text."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import POSES, ROOT, compile_package, run_cli

from op2motion.cli import build_parser

README = (ROOT / "README.md").read_text(encoding="utf-8")
DOCS = ROOT / "docs"
#: Every page a reader may open: the README and the docs/ pages.
ALL_TEXT = "\n".join([README, *(p.read_text(encoding="utf-8") for p in sorted(DOCS.glob("*.md")))])


def _example_lines() -> list[str]:
    section = (DOCS / "cli.md").read_text(encoding="utf-8").split("## Examples", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```bash\n(.*?)```", section, re.S)
    return [line for block in blocks for line in block.splitlines() if line.startswith("op2motion ")]


SKIP_DIRS = {".git", ".venv", "__pycache__", ".pytest_cache", ".hypothesis", ".ruff_cache", "build", "dist"}


def _repository_files() -> list[str]:
    """The tracked files (git), or, in a copy without git (CI), every file outside build and cache folders."""
    done = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True)
    if done.returncode == 0 and done.stdout:
        return [name.decode() for name in done.stdout.split(b"\0") if name]
    files = []
    for folder, dirs, names in os.walk(ROOT):   # pruned as it goes: caches other tests write meanwhile are skipped
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.endswith(".egg-info")]
        files += [str((Path(folder) / n).relative_to(ROOT)) for n in names]
    return files


@pytest.fixture(scope="module")
def clone(tmp_path_factory):
    """The repository's files copied as a fresh clone would have them."""
    dest = tmp_path_factory.mktemp("clone")
    for name in _repository_files():
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes((ROOT / name).read_bytes())
    compile_package(dest)
    return dest


def test_the_readme_has_examples_for_every_command():
    commands = {line.split()[1] for line in _example_lines()}
    assert {"fk", "convert", "plot", "arm-ik", "optimize", "validate", "import-action", "export", "urdf",
            "library"} <= commands


def _physics(line: str) -> bool:
    return "--validate" in line or line.split()[1] == "validate"


#: Commands whose examples take seconds without an engine: a library build (worker processes), a walk or a motion
#: planned, a pose optimised, a figure drawn.
SLOW_COMMANDS = ("library", "walk", "motion", "optimize", "plot")


def _marks(line: str) -> list[pytest.MarkDecorator]:
    """physics where the example runs an engine; slow where it takes seconds without (:data:`SLOW_COMMANDS`)."""
    return [pytest.mark.physics] if _physics(line) else [pytest.mark.slow] if line.split()[1] in SLOW_COMMANDS else []


@pytest.mark.parametrize("line", [pytest.param(line, marks=_marks(line)) for line in _example_lines()],
                         ids=lambda line: " ".join(line.split()[:3]))
def test_readme_example_runs_as_written(clone, line, monkeypatch, capsys):
    """Each line in a fresh copy of the repository, through the command line's own entry (``main``, in this process:
    a program started per line cost the suite a second or two of imports each; the quickstart's program itself is
    run by tests/test_docs.py)."""
    argv = shlex.split(line)
    monkeypatch.chdir(clone)
    code, _, err = run_cli(capsys, *argv[1:])
    assert code == 0, err
    for flag in ("-o", "--out", "--plot", "--gui-png"):        # the files it promised exist
        if flag in argv:
            written = argv[argv.index(flag) + 1]
            assert written.startswith("out/") and (clone / written).exists(), flag   # examples write under out/


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


def _python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


#: Runs each example given on standard input (JSON: a list of sources) in a namespace of its own, in one process
#: (each would otherwise import the package and its engines again), printing SEPARATOR after each one's output.
SEPARATOR = "=== next example ==="
RUN_EACH = f"""
import json, sys
for source in json.load(sys.stdin):
    exec(compile(source, "<example>", "exec"), {{"__name__": "__main__"}})
    print({SEPARATOR!r}, flush=True)
"""


@pytest.mark.physics
def test_the_python_api_examples_run(clone):
    """The README's example and the API page's first one and its tasks example, as written, in a fresh copy (one
    after the other in one process, each in a namespace of its own)."""
    import json

    front = _python_blocks(README.split("## In Python", 1)[1])[0]
    page = _python_blocks((DOCS / "python.md").read_text(encoding="utf-8"))
    tasks = next(b for b in page if "op2motion.tasks" in b)
    done = subprocess.run([sys.executable, "-c", RUN_EACH], input=json.dumps([front, page[0], tasks]), cwd=clone,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    outputs = done.stdout.split(SEPARATOR + "\n")
    assert len(outputs) == 4 and outputs[3] == "", done.stdout
    assert "True [] " in outputs[0] and "True reached" in outputs[0] and "\nFalse 0.2" in outputs[0], outputs[0]
    assert "True [] " in outputs[1] and "\nTrue\n" in outputs[1] and "True reached" in outputs[1], outputs[1]
    assert outputs[2].startswith("True None ") and "['plot']" in outputs[2] and "STABLE" in outputs[2], outputs[2]


def test_the_static_torque_table_is_the_codes():
    """The static torques (docs/model.md, regenerated by tools/readme_figures.py) are what pinocchio gives today."""
    from op2motion.formats.posefile import read_pose
    from op2motion.model.dynamics import dynamics_for
    from op2motion.robot.specfile import default_spec

    spec = default_spec()
    text = ALL_TEXT
    printed = re.findall(r"^\| (\w+) \| (double|left|right) \| (\w+) \| ([\d.]+) \| (\d+%) \|$", text, re.M)
    assert len(printed) >= 6
    for name, support, joint, torque, share in printed:     # each row recomputed from the pose and support it names
        report = dynamics_for(spec).static_torques(read_pose(POSES / f"{name}.json", spec).servo, support)
        assert (report.worst_joint, f"{abs(report.worst_torque_nm):.2f}", f"{report.worst_ratio:.0%}") == (
            joint, torque, share), name


def test_the_book_poses_margins_are_the_committed_ones():
    import json

    from helpers import POSES

    for name in ("book_2_44", "book_2_45", "book_2_46", "book_2_47"):
        margin = json.loads((POSES / f"{name}.json").read_text())["metrics"]["stability_margin_full_m"]
        assert f"{margin * 1000:.1f} mm" in ALL_TEXT.split("The book's four scenarios", 1)[1].split("\n* ", 1)[0], name


def test_the_development_map_names_every_wing_and_module():
    """The map in docs/development.md lists each sub-package (``name/``) and loose module (``name.py``) of
    op2motion, and nothing that is not there."""
    section = (DOCS / "development.md").read_text(encoding="utf-8")
    block = re.findall(r"```\n(.*?)```", section, re.S)[0]
    named = set()
    for line in block.splitlines():
        head = line[:26].strip()                      # the first column: names separated by commas
        named |= {n.strip() for n in head.split(",") if n.strip()}
    package = ROOT / "op2motion"
    present = {p.name for p in package.glob("*.py")} | {f"{p.name}/" for p in package.iterdir()
                                                        if (p / "__init__.py").is_file()}
    assert named == present
