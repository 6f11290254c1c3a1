"""The robot's transport (packets, tables, clock, port, client, robot, safety, session and the 8 ms loop) imports
without the physics engines, the optimiser, the plots or the studio: the robot's own PC can run the loop with numpy
and pyserial alone. Checked in a fresh interpreter where importing any of those fails."""

from __future__ import annotations

import subprocess
import sys

from helpers import ROOT

TRANSPORT = ("protocol", "tables", "clock", "link", "port", "client", "robot", "safety", "session", "stopping", "loop")
#: What the transport must not need (the test makes importing each fail).
HEAVY = ("pybullet", "pybullet_utils", "mujoco", "pinocchio", "numba", "scipy", "matplotlib", "pyswarms", "optuna",
         "ray", "viser", "trimesh", "yourdfpy", "tqdm", "cmeel")

PROGRAM = f"""
import importlib, importlib.abc, sys
class Blocked(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in {set(HEAVY)!r}:
            raise ImportError("not installed here: " + name)
sys.meta_path.insert(0, Blocked())
for module in {TRANSPORT!r}:
    importlib.import_module("op2motion.bus." + module)
print("imported")
"""


def test_the_transport_and_its_loop_import_without_the_engines():
    done = subprocess.run([sys.executable, "-c", PROGRAM], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == "imported", done.stderr[-2000:]


def test_the_check_is_not_vacuous():
    """The same program fails when what it blocks is needed (numpy, which the transport does need)."""
    program = PROGRAM.replace(repr(set(HEAVY)), repr({*HEAVY, "numpy"}))
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert done.returncode != 0 and "not installed here" in done.stderr
