"""The lint step: ruff on everything, mypy on the package (both configured in pyproject.toml; the whole package
under --strict), in one run that also shows what an editor sees through the public API and of every task's result."""

from __future__ import annotations

import ast
import re
import subprocess
import sys

import pytest
from helpers import ROOT


def test_ruff_is_clean():
    done = subprocess.run([sys.executable, "-m", "ruff", "check", "op2motion", "tests", "tools", "examples"],
                          cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.slow
def test_mypy_is_clean_and_sees_the_public_api(tmp_path):
    """The package is clean under --strict (pyproject.toml), and
    ``reveal_type(op2motion.solve)`` is a function type, not Any. One run, sharing mypy's cache with a developer's
    (a second run with other options would throw it away)."""
    probe = tmp_path / "probe.py"
    tasks = _task_functions()
    probe.write_text("import op2motion\nreveal_type(op2motion.solve)\nreveal_type(op2motion.check)\n"
                     + "".join(f"import op2motion.tasks.{m}\nreveal_type(op2motion.tasks.{m}.{f})\n" for m, f in tasks),
                     encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "mypy", "op2motion", str(probe)], cwd=ROOT, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    revealed = [line for line in done.stdout.splitlines() if "Revealed type" in line]
    assert len(revealed) == 2 + len(tasks) and not any('"Any"' in line for line in revealed), done.stdout
    assert "def (" in revealed[0], revealed[0]
    for line in revealed[2:]:                     # each task's result is a TaskResult of a type, not of Any
        value = re.search(r"-> op2motion\.tasks\.result\.TaskResult\[(.*)\]\"$", line)
        assert value is not None and value.group(1) not in ("Any", "None"), line


def _task_functions() -> list[tuple[str, str]]:
    """Every public function of op2motion/tasks/ that returns a TaskResult: (module, name)."""
    found = []
    for path in sorted((ROOT / "op2motion" / "tasks").glob("*.py")):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.FunctionDef) and not node.name.startswith("_") and node.returns is not None \
                    and ast.unparse(node.returns).startswith("TaskResult"):
                found.append((path.stem, node.name))
    assert len(found) >= 20, found
    return found


def test_the_whole_package_is_held_to_strict():
    """mypy runs with --strict on the whole package, and no override turns one of its flags off for a module of
    op2motion (the overrides are for third-party packages without type information)."""
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]
    assert config["strict"] is True and config["files"] == ["op2motion"]
    for override in config["overrides"]:
        modules = [override["module"]] if isinstance(override["module"], str) else override["module"]
        assert not any(m.split(".")[0] == "op2motion" for m in modules), override
        assert not any(override.get(flag) is False for flag in STRICT_FLAGS), override


#: --strict's per-module flags (mypy 2.x; warn_unused_ignores and warn_redundant_casts are set for the package).
STRICT_FLAGS = ("disallow_any_generics", "disallow_subclassing_any", "disallow_untyped_calls", "disallow_untyped_defs",
                "disallow_incomplete_defs", "check_untyped_defs", "disallow_untyped_decorators", "warn_return_any",
                "no_implicit_reexport", "strict_equality", "extra_checks")
