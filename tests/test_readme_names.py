"""Every name the Python examples of the README and docs/ use can be imported as they show it: each
``from X import A, B``, each ``import X as Y`` and every attribute they take of such a module (``op2.check``,
``op2.Setup``, ...)."""

from __future__ import annotations

import importlib
import re

import pytest
from helpers import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCKS = [b for p in PAGES for b in re.findall(r"```python\n(.*?)```", p.read_text(encoding="utf-8"), re.S)]


def _names() -> list[tuple[str, str]]:
    """(module, name) pairs: ``from module import name`` and ``alias.name`` of ``import module as alias``."""
    out: list[tuple[str, str]] = []
    for code in BLOCKS:
        code = re.sub(r"#.*", "", code)                 # comments name files (specs/op2.toml), not attributes
        aliases = {}
        for module, names in re.findall(r"^\s*from ([\w.]+) import ([\w, ]+)", code, re.M):
            out += [(module, n.strip()) for n in names.split(",") if n.strip()]
        for module, alias in re.findall(r"^\s*import ([\w.]+)(?: as (\w+))?", code, re.M):
            aliases[alias or module] = module
            out.append((module, ""))
        for alias, module in aliases.items():
            out += [(module, n) for n in re.findall(rf"\b{re.escape(alias)}\.(\w+)", code)]
    return sorted(set(out))


def test_the_readme_shows_python_examples():
    assert len(BLOCKS) >= 2 and any("SteerableWalk" in b for b in BLOCKS) and any("GetUp" in b for b in BLOCKS)


@pytest.mark.parametrize("module, name", _names(), ids=lambda v: v or "module")
def test_every_name_the_readme_shows_imports(module, name):
    imported = importlib.import_module(module)
    if name:
        assert hasattr(imported, name), f"{module}.{name}"
