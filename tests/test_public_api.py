"""The public API as tools see it: every name in ``op2motion.__all__`` is imported explicitly for type checkers (while
``import op2motion`` stays free of work, ``tests/test_startup.py``), resolves at run time to the same object, and
mypy --strict sees real types through it (tests/test_lint.py, one mypy run); the package says it is typed
(``py.typed``)."""

from __future__ import annotations

import ast

import pytest
from helpers import ROOT

import op2motion

INIT = ROOT / "op2motion" / "__init__.py"


def _typed_names() -> dict[str, tuple[str, str]]:
    """Name -> (module, attribute) of the ``if TYPE_CHECKING:`` imports of ``op2motion/__init__.py``."""
    tree = ast.parse(INIT.read_text(encoding="utf-8"))
    block = next(n for n in tree.body if isinstance(n, ast.If) and getattr(n.test, "id", "") == "TYPE_CHECKING")
    out = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom) and node.module, ast.dump(node)
        for alias in node.names:
            out[alias.asname or alias.name] = (node.module.removeprefix("op2motion."), alias.name)
    return out


def test_the_typed_imports_are_the_run_time_api():
    api = op2motion._API
    assert _typed_names() == api
    assert sorted(op2motion.__all__) == sorted([*api, "__version__"])


@pytest.mark.parametrize("name", sorted(op2motion._API))
def test_each_public_name_resolves(name):
    module, attr = op2motion._API[name]
    import importlib

    assert getattr(op2motion, name) is getattr(importlib.import_module(f"op2motion.{module}"), attr)


def test_the_package_is_marked_typed():
    assert (ROOT / "op2motion" / "py.typed").is_file()
    assert '"op2motion" = ["py.typed"]' in (ROOT / "pyproject.toml").read_text(encoding="utf-8")


#: Public methods whose tuple is a value, not a bundle of results: a support rectangle (front, back, left, right) [m].
VALUE_TUPLES = {"PostureProblem.extents", "Spec.sole_extents"}


def test_the_public_api_returns_types_not_dicts_or_bare_tuples():
    """Every public function, and every public method of a public class, returns a named type: no ``dict[str, Any]``
    (``as_dict`` aside: that is the JSON of a result) and no bare tuple of results."""
    import inspect

    found = []
    for name in op2motion._API:
        obj = getattr(op2motion, name)
        members = [(name, obj)] if inspect.isfunction(obj) else [
            (f"{name}.{m}", f) for m, f in inspect.getmembers(obj, inspect.isfunction)
            if not m.startswith("_") and m != "as_dict"] if inspect.isclass(obj) else []
        for label, fn in members:
            returned = str(inspect.signature(fn).return_annotation).replace("typing.", "")
            bare = returned.startswith(("tuple", "Tuple")) and not returned.endswith(", ...]")   # (X, ...): a sequence
            if (bare or "dict[str, Any]" in returned) and label not in VALUE_TUPLES:
                found.append((label, returned))
    assert found == []
