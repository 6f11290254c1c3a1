"""One module of a package loaded without the package's ``__init__`` (op2motion.processes.imports): pyswarms'
GlobalBestPSO as ``optimize`` loads it, the same optimiser as the whole package's, without SciPy."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from op2motion.processes import imports

#: A package whose ``__init__`` leaves a mark when it runs; ``heavy.sub.light`` imports a sibling module and a name
#: the stand-in of ``heavy.sub`` must provide; ``heavy.sub.needy`` needs what only the real ``__init__`` defines.
FILES = {
    "__init__.py": "open(__file__ + '.ran', 'w').close()\nFROM_INIT = 1\n",
    "tools.py": "def double(x):\n    return 2 * x\n",
    "sub/__init__.py": "open(__file__ + '.ran', 'w').close()\nfrom .base import Base\n",
    "sub/base.py": "class Base:\n    pass\n",
    "sub/light.py": "from ..tools import double\nfrom . import Base\n\nclass Light(Base):\n    value = double(21)\n",
    "sub/needy.py": "from .. import FROM_INIT\n",
}


@pytest.fixture()
def heavy(tmp_path, monkeypatch):
    """The package of :data:`FILES` on the path (a fresh name each test), nothing of it loaded."""
    name = f"heavy_{tmp_path.name.replace('-', '_')}"
    for rel, text in FILES.items():
        (tmp_path / name / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name / rel).write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(imports, "_LOADED", {})
    yield name, tmp_path / name
    for module in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
        del sys.modules[module]


def test_the_module_loads_without_the_inits_and_leaves_nothing_behind(heavy):
    name, root = heavy
    light = imports.lean_import(f"{name}.sub.light", (name, f"{name}.sub"), {f"{name}.sub": {"Base": "base"}})
    assert light.Light.value == 42 and issubclass(light.Light, light.Base)
    assert not (root / "__init__.py.ran").exists() and not (root / "sub" / "__init__.py.ran").exists()
    assert not [m for m in sys.modules if m.startswith(name)]
    assert imports.lean_import(f"{name}.sub.light", (name, f"{name}.sub")) is light     # once per process
    whole = __import__(f"{name}.sub.light", fromlist=["Light"])        # a later import is the whole package's
    assert whole is not light and (root / "__init__.py.ran").exists() and sys.modules[name].FROM_INIT == 1


def test_a_module_that_needs_its_package_init_gets_it(heavy):
    name, root = heavy
    needy = imports.lean_import(f"{name}.sub.needy", (name, f"{name}.sub"))
    assert needy.FROM_INIT == 1 and (root / "__init__.py.ran").exists()
    assert sys.modules[f"{name}.sub.needy"] is needy                   # the usual import, kept as usual


def test_a_package_loaded_already_is_used_as_it_is(heavy):
    name, root = heavy
    package = __import__(name)
    light = imports.lean_import(f"{name}.sub.light", (name, f"{name}.sub"))
    assert sys.modules[f"{name}.sub.light"] is light and sys.modules[name] is package


#: In a fresh interpreter: the same seeded swarm with the lean GlobalBestPSO, then with the whole package's.
SWARMS = """
import json, sys
import numpy as np
from op2motion.posture.pso import contained_pyswarms, global_best_pso

def run(cls):
    np.random.seed(7)
    with contained_pyswarms():
        opt = cls(n_particles=12, dimensions=3, options={"w": 0.8, "c1": 2.0, "c2": 2.0},
                  bounds=(-np.ones(3), np.ones(3)), bh_strategy="nearest")
        cost, pos = opt.optimize(lambda x: ((x - 0.3) ** 2).sum(axis=1), iters=30, verbose=False)
    return [cost, list(pos), list(opt.cost_history)]

lean = run(global_best_pso())
after_lean = sorted({m.split(".")[0] for m in sys.modules} & {"scipy", "pyswarms"})
from pyswarms.single import GlobalBestPSO
print(json.dumps({"lean": lean, "whole": run(GlobalBestPSO), "after_lean": after_lean,
                  "same_class": GlobalBestPSO is global_best_pso()}))
"""


def test_the_lean_global_best_is_pyswarms_own_without_scipy():
    done = subprocess.run([sys.executable, "-c", SWARMS], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout.splitlines()[-1])
    assert found["after_lean"] == [], found["after_lean"]      # no SciPy loaded, no pyswarms module left behind
    assert found["lean"] == found["whole"] and not found["same_class"]


#: In a fresh interpreter: numba's CPU target started (its array maths module checks for BLAS) inside the lent
#: SciPy BLAS table, and what is loaded inside and after.
NUMBA_BLAS = """
import json, sys
from op2motion.processes.imports import scipy_blas_for_numba
with scipy_blas_for_numba():
    import numba.np.arraymath
    inside = {"blas": numba.np.arraymath._HAVE_BLAS, "linalg": "scipy.linalg" in sys.modules}
after = "scipy.linalg.cython_blas" in sys.modules
import scipy.linalg.cython_blas
print(json.dumps({**inside, "after": after, "usual": "dgemm" in scipy.linalg.cython_blas.__pyx_capi__}))
"""


def test_numba_finds_scipys_blas_without_scipy_linalg():
    done = subprocess.run([sys.executable, "-c", NUMBA_BLAS], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.splitlines()[-1]) == {"blas": True, "linalg": False, "after": False, "usual": True}
