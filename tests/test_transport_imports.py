"""The robot's transport (packets, tables, clock, port, client, robot, safety, session and the 8 ms loop) imports
without the physics engines, the optimiser, the plots or the studio: the robot's own PC can run the loop with numpy
and pyserial alone. Checked in a fresh interpreter where importing any of those fails."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

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


#: What the robot's own PC needs besides the package (pyproject's dependencies of the transport).
TRANSPORT_NEEDS = ("numpy", "numpy.libs", "serial")
#: The package's modules the transport must not load (the applications' and the physics' layers).
NOT_LOADED = ("op2motion.physics", "op2motion.gait", "op2motion.motion", "op2motion.posture", "op2motion.model",
              "op2motion.kinematics")


def test_the_transport_runs_in_a_venv_with_only_numpy_and_pyserial(tmp_path):
    """A fresh virtual environment whose only packages are numpy, pyserial and op2motion's source (linked, not
    installed: pip would fetch the package's other dependencies): the transport imports, loads nothing of the
    physics, the gait, the motions or the model, and its loop's pieces work (a tick's goals to servo ticks)."""
    import os
    import sysconfig
    import venv

    venv.EnvBuilder(with_pip=False).create(tmp_path / "venv")
    site = tmp_path / "site"
    site.mkdir()
    packages = Path(sysconfig.get_paths()["purelib"])
    for name in TRANSPORT_NEEDS:
        if (packages / name).exists():
            os.symlink(packages / name, site / name)
    os.symlink(ROOT / "op2motion", site / "op2motion")
    python = tmp_path / "venv" / "bin" / "python"
    purelib = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    Path(purelib, "transport.pth").write_text(str(site) + "\n")
    program = f"""
import importlib, sys
for module in {TRANSPORT!r}:
    importlib.import_module("op2motion.bus." + module)
loaded = sorted(m for m in sys.modules if m.startswith({NOT_LOADED!r}))
assert not loaded, loaded
for heavy in {HEAVY!r}:
    try:
        importlib.import_module(heavy)
    except ImportError:
        continue
    raise SystemExit("this venv has " + heavy)
from op2motion.robot.joints import servo_to_ticks
from op2motion.robot.specfile import default_spec
spec = default_spec()
import numpy as np
print("ticks", int(servo_to_ticks(np.zeros(len(spec.joints)), spec)[0]))
"""
    done = subprocess.run([python, "-I", "-c", program], capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert done.returncode == 0 and done.stdout.split() == ["ticks", "2048"], done.stdout + done.stderr[-2000:]


def test_the_bus_holds_the_transport_and_the_emulator_only():
    """What runs on the robot through the transport (moves checked in physics, the walks, the robot commands) lives
    in op2motion/onrobot, not beside it."""
    modules = {p.stem for p in (ROOT / "op2motion" / "bus").glob("*.py")} - {"__init__"}
    assert modules == set(TRANSPORT) | {"realtime"}, sorted(modules ^ (set(TRANSPORT) | {"realtime"}))
    assert {p.name for p in (ROOT / "op2motion" / "bus").iterdir() if p.is_dir() and p.name != "__pycache__"} == {
        "emulator"}
