"""The package's structure: imports run one way, from higher layers to lower ones, with no circle.

The graph is drawn from every ``import`` in the source (module level and inside functions), so lazy imports count.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path
from typing import NamedTuple

import pytest
from helpers import source_tree

PACKAGE = Path(__file__).resolve().parents[1] / "op2motion"
#: Layers, lowest first. A module may import modules of lower layers and of its own package; never higher ones.
LAYERS = [
    {"jsonout"},
    {"errors", "version", "processes"},
    {"book", "fileio", "bench_wall"},
    {"robot"},
    {"kinematics", "formats"},
    {"model"},
    {"posture", "physics"},
    {"motion"},
    {"gait"},
    {"bus"},
    {"onrobot"},
    {"workflow"},
    {"studio"},
    {"figures", "library", "bench"},
    {"tune"},
    {"tasks"},
    {"commands"},
    {"cli"},
    {"__main__", "__init__"},
]


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__" and len(parts) > 1:
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path, tree: ast.Module) -> set[str]:
    """op2motion modules imported by one file (``tree``, parsed; relative imports resolved), as dotted names below
    the package."""
    name = _module_name(path)
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - (node.level - 1)] if node.level > 1 else package
                target = base + (node.module.split(".") if node.module else [])
                for alias in node.names:   # `from . import x` may name a module
                    candidate = ".".join(target + [alias.name])
                    found.add(candidate if _exists(candidate) else ".".join(target))
            elif node.module and node.module.startswith("op2motion"):
                target = node.module.removeprefix("op2motion").lstrip(".")
                for alias in node.names:   # `from op2motion.x import y` may name a module
                    candidate = f"{target}.{alias.name}" if target else alias.name
                    found.add(candidate if _exists(candidate) else target)
        elif isinstance(node, ast.Import):
            found |= {a.name.removeprefix("op2motion").lstrip(".") for a in node.names
                      if a.name.startswith("op2motion")}
    return {f for f in found if f and f != name}


def _exists(dotted: str) -> bool:
    base = PACKAGE.joinpath(*dotted.split("."))
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def _layer(module: str) -> int:
    top = module.split(".")[0]
    for i, names in enumerate(LAYERS):
        if top in names:
            return i
    raise AssertionError(f"module {module} is in no layer: add it to LAYERS")


class _Facts(NamedTuple):
    """What the tests read from one source file (the syntax tree itself is not kept)."""

    imports: set[str]
    functions: list[tuple[str, int, int]]       # (path:name, parameters but self and cls, lines)
    documented: bool


def _facts_of(path: Path) -> _Facts:
    tree = source_tree(path)
    functions = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            params = [*a.posonlyargs, *a.args, *a.kwonlyargs] + ([a.vararg] if a.vararg else []) + (
                [a.kwarg] if a.kwarg else [])
            functions.append((f"{path.relative_to(PACKAGE.parent)}:{node.name}",
                              len([p for p in params if p.arg not in ("self", "cls")]),
                              node.end_lineno - node.lineno + 1))
    return _Facts(_imports(path, tree), functions, bool(ast.get_docstring(tree)))


@functools.cache
def _facts() -> dict[Path, _Facts]:
    """Every source file's facts, read once per test process when a test first asks (not while collecting)."""
    return {p: _facts_of(p) for p in sorted(PACKAGE.rglob("*.py"))}


def _graph() -> dict[str, set[str]]:
    return {_module_name(p): f.imports for p, f in _facts().items()}


@pytest.mark.parametrize("module", sorted(_module_name(p) for p in PACKAGE.rglob("*.py")))
def test_imports_run_downwards(module):
    for target in _graph()[module]:
        same_package = target.split(".")[0] == module.split(".")[0]
        assert same_package or _layer(target) < _layer(module), f"{module} imports {target} (a higher layer)"


def test_no_circles():
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in graph.get(node, ()):
            if state.get(nxt) == 1:
                raise AssertionError("import circle: " + " -> ".join(path + [nxt]))
            if nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    graph = _graph()
    for module in graph:
        if module not in state:
            visit(module, [module])


#: What the optimiser (``posture``) may not import: file formats, physics, the workflow and the library builder.
OPTIMISER_FORBIDDEN = ("formats", "physics", "workflow", "library")


def optimiser_violations(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """(module, target) pairs where the optimiser imports what :data:`OPTIMISER_FORBIDDEN` names; every forbidden
    prefix must name a package that exists (a renamed one would make the rule silently empty)."""
    for prefix in OPTIMISER_FORBIDDEN:
        if not _exists(prefix):
            raise AssertionError(f"the rule names {prefix!r}, which is no op2motion module")
    return [(m, t) for m, targets in graph.items() if m.split(".")[0] == "posture" for t in sorted(targets)
            if t.split(".")[0] in OPTIMISER_FORBIDDEN]


def test_the_optimiser_depends_on_no_file_format_nor_physics():
    assert optimiser_violations(_graph()) == []


def test_the_optimiser_rule_catches_a_planted_import():
    graph = _graph()
    planted = {**graph, "posture.solve": graph["posture.solve"] | {"formats.posefile"}}
    assert optimiser_violations(planted) == [("posture.solve", "formats.posefile")]


def test_every_subpackage_is_packaged():
    """A sub-package missing from ``pyproject.toml`` works in the source tree and is absent from an install."""
    import re

    text = (PACKAGE.parent / "pyproject.toml").read_text()
    listed = set(re.findall(r'"(op2motion(?:\.\w+)*)"', re.search(r"packages = \[(.*?)\]", text).group(1)))
    present = {".".join(("op2motion", *p.parent.relative_to(PACKAGE).parts)) for p in PACKAGE.rglob("__init__.py")}
    assert present <= listed, f"not in pyproject.toml packages: {sorted(present - listed)}"


MAX_TOP_LEVEL_MODULES = 12       # loose modules in op2motion/ beside its sub-packages
MAX_PARAMETERS = 8               # per function (self and cls not counted)
MAX_FUNCTION_LINES = 60
UNROLLED_KERNELS = {"op2motion/kinematics/projection.py:_chunk",    # the book's projection formulas, one per line
                    "op2motion/posture/kernel.py:_swarm"}          # one compiled loop: split, it ran 2.5x slower


def _functions():
    for facts in _facts().values():
        yield from facts.functions


def test_the_package_shows_its_wings():
    loose = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(loose) <= MAX_TOP_LEVEL_MODULES, loose


def test_no_function_takes_more_than_8_parameters():
    heavy = [(name, count) for name, count, _ in _functions() if count > MAX_PARAMETERS]
    assert heavy == []


def test_no_function_is_longer_than_60_lines():
    long = [(name, lines) for name, _, lines in _functions()
            if lines > MAX_FUNCTION_LINES and name not in UNROLLED_KERNELS]
    assert long == []


#: What the rest of the code may use of the physics package: its public API, its report types, the lean sweeps.
PHYSICS_API = {"physics", "physics.report", "physics.sweeps"}
#: The one module outside physics that runs an engine by itself: the emulated OP2's body steps an engine in real time
#: behind the bus (its own loop, driven by the servos' registers, not a check).
ENGINE_USERS = {"bus.emulator.body": {"physics.engine", "physics.sensors", "physics.body"}}


def test_physics_check_is_the_only_way_into_physics():
    """Outside the physics package (and the tests), nothing runs an engine or the loop by itself."""
    for module, targets in _graph().items():
        if not module.startswith("physics"):
            used = {t for t in targets if t.startswith("physics")}
            allowed = PHYSICS_API | ENGINE_USERS.get(module, set())
            assert used <= allowed, (module, used - allowed)
    for folder in ("tools", "examples"):
        for path in (PACKAGE.parent / folder).glob("*.py"):
            used = set(re.findall(r"op2motion\.(physics[\w.]*)", path.read_text(encoding="utf-8")))
            assert used <= PHYSICS_API, (path.name, used - PHYSICS_API)
            assert "sys.path" not in path.read_text(encoding="utf-8"), f"{path.name} reaches into another folder"


def test_every_module_says_what_it_is():
    """Every module of the package, packages included, opens with a docstring."""
    bare = [str(p.relative_to(PACKAGE)) for p, facts in _facts().items() if not facts.documented]
    assert bare == []
