"""One module of a third-party package, loaded without the package ``__init__`` that would load everything else.

``import pyswarms`` loads every optimiser and topology pyswarms has, and its ring and random topologies load SciPy's
spatial and sparse-graph modules: 0.4 s of a 1-s ``optimize``, which uses one optimiser class; numba's compiled
code finds BLAS in ``scipy.linalg.cython_blas``, and importing that loads all of ``scipy.linalg`` first (0.1-0.2 s,
:func:`scipy_blas_for_numba`). :func:`lean_import`
imports just the module that defines what is used, with empty packages of the same path standing in for the heavy
``__init__`` s while it loads; the module's own code and what it imports run unchanged. Afterwards every module of
the skipped packages that the load added is taken out of ``sys.modules`` again (what was loaded lives on in the
objects handed back), so nothing half-initialised stays behind: a later ``import pyswarms`` anywhere loads the whole
package as usual.

Where a skipped package is loaded already, or the stand-ins cannot be made (a package that is not a folder of
files, a module that needs its package's ``__init__`` after all), the whole package is imported the usual way. The
stand-ins are in ``sys.modules`` only while the load runs (under a lock): another thread importing the same package
at that moment would see them.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import os
import sys
import threading
import types
from typing import Iterator, Mapping, Sequence

_LOCK = threading.Lock()
_LOADED: dict[str, types.ModuleType] = {}


def lean_import(module: str, skipped: Sequence[str], provides: Mapping[str, Mapping[str, str]] | None = None
                ) -> types.ModuleType:
    """The module ``module`` loaded with the packages ``skipped`` (outermost first, each ``module``'s ancestor)
    standing in empty (see the module docstring); ``provides``: what a stand-in must hold for the modules that
    import from it, {package: {name: its submodule that defines it}} (what its real ``__init__`` would give).
    Loaded once per process."""
    with _LOCK:
        if module not in _LOADED:
            _LOADED[module] = _load(module, skipped, provides or {})
        return _LOADED[module]


#: SciPy's table of BLAS functions for compiled code, and the package whose ``__init__`` it is loaded without.
SCIPY_BLAS, SCIPY_LINALG = "scipy.linalg.cython_blas", "scipy.linalg"


@contextlib.contextmanager
def scipy_blas_for_numba() -> Iterator[None]:
    """While inside, :data:`SCIPY_BLAS` is in ``sys.modules``, loaded without ``scipy.linalg``'s ``__init__``:
    numba's CPU target imports it when it starts (to call BLAS from compiled code), and through ``scipy.linalg``
    that import costs 0.1-0.2 s of SciPy's decompositions and array-API layer that no kernel of op2motion uses.
    Wrap a process's first numba kernel call in it (:class:`~op2motion.processes.compiled.CompileOnce` does).
    Afterwards the entry is taken out again (unless ``scipy.linalg`` was loaded meanwhile), so that a later
    ``import scipy.linalg.cython_blas`` loads it the usual way, under its package."""
    lent = None
    if SCIPY_BLAS not in sys.modules and SCIPY_LINALG not in sys.modules:
        with contextlib.suppress(ImportError):          # no SciPy: numba says what it misses, as before
            lent = sys.modules[SCIPY_BLAS] = lean_import(SCIPY_BLAS, (SCIPY_LINALG,))
    try:
        yield
    finally:
        if lent is not None and SCIPY_LINALG not in sys.modules and sys.modules.get(SCIPY_BLAS) is lent:
            del sys.modules[SCIPY_BLAS]


def _load(module: str, skipped: Sequence[str], provides: Mapping[str, Mapping[str, str]]) -> types.ModuleType:
    if not any(name in sys.modules for name in skipped):
        before = set(sys.modules)
        try:
            for name in skipped:
                sys.modules[name] = _stand_in(name)
                for attr, sub in provides.get(name, {}).items():
                    setattr(sys.modules[name], attr, getattr(importlib.import_module(f"{name}.{sub}"), attr))
            return importlib.import_module(module)
        except ImportError:
            pass                    # loaded the usual way below, with nothing of this attempt left
        finally:
            _forget(before, skipped)
    return importlib.import_module(module)


def _stand_in(name: str) -> types.ModuleType:
    """An empty package ``name`` that finds its submodules where the real one would (its ``__init__`` not run)."""
    parent, _, last = name.rpartition(".")
    if parent:
        where = [os.path.join(p, last) for p in importlib.import_module(parent).__path__]
    else:
        spec = importlib.util.find_spec(name)
        if spec is None or not spec.submodule_search_locations:
            raise ImportError(f"{name} is not a package of files")
        where = list(spec.submodule_search_locations)
    if not any(os.path.isfile(os.path.join(w, "__init__.py")) for w in where):
        raise ImportError(f"{name} is not a package of files")
    stand_in = types.ModuleType(name)
    stand_in.__path__ = where
    stand_in.__package__ = name
    return stand_in


def _forget(before: set[str], skipped: Sequence[str]) -> None:
    """Take every module of the ``skipped`` packages added since ``before`` out of ``sys.modules``."""
    for name in set(sys.modules) - before:
        if any(name == s or name.startswith(s + ".") for s in skipped):
            with contextlib.suppress(KeyError):
                del sys.modules[name]

