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
