"""Shared fixtures: the shipped spec, a seeded RNG, the stock action file; op2motion compiled once for the many
subprocesses the tests start (CLI runs, examples, library workers), which would otherwise each compile it again
where Python is told not to write bytecode (PYTHONDONTWRITEBYTECODE), and the test modules' own."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys

#: One BLAS thread per test process (and the subprocesses it starts): the test processes fill the cores already, and
#: OpenBLAS threads spinning against them cost the fast lane 6 % of its CPU. Set before NumPy loads OpenBLAS.
for _threads in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_threads, "1")

import numpy as np
import pytest
import warm_kernels
from helpers import ROOT, SEED, STOCK, compile_package

from op2motion.robot.spec import Spec
from op2motion.robot.specfile import default_spec

#: The test modules' bytecode (their asserts rewritten by pytest) is kept in ``tests/__pycache__`` (git-ignored) even
#: where Python is told not to write bytecode: each test process otherwise rewrites all of them again (2-3 s each).
sys.dont_write_bytecode = False


@pytest.fixture(scope="session")
def spec() -> Spec:
    return default_spec()


@pytest.fixture()
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def stock_action_bytes() -> bytes:
    """The stock ROBOTIS motion_4096.bin (copied from the ROBOTIS framework's Data folder)."""
    return STOCK.read_bytes()


@pytest.fixture(scope="module")
def pybullet_robot(spec):
    """A PyBullet client (no GUI) with the spec's URDF loaded with self-collision, for exact distances."""
    import pybullet as pb
    from pybullet_utils import bullet_client

    from op2motion.model.urdf import build_urdf
    from op2motion.physics.pybullet_engine import load_robot

    client = bullet_client.BulletClient(connection_mode=pb.DIRECT)
    robot = load_robot(client, build_urdf(spec), pb.URDF_USE_SELF_COLLISION | pb.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT)
    yield client, robot
    client.disconnect()


#: Modules holding the longest tests (tens of seconds each, some in a module fixture): collected first, so that no
#: core idles at the end while one of them finishes (the others' tests are stolen around them).
LONG_FIRST = ("test_lean_sweeps.py", "test_walk_robust.py", "test_bench.py", "test_studio.py", "test_cluster.py")


#: Test processes beyond one per core: many tests wait (on the programs they start, a pseudo-terminal's bytes, a
#: browser, a Ray head), and one more process fills those waits. Measured on 2 cores: 2 processes 4:33-4:49, 3 processes
#: 4:08, 4 processes 4:18 with the browser test timing out (docs/development.md).
EXTRA_WORKERS = 1


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto``: one test process per core and :data:`EXTRA_WORKERS` (the bus tests run in lockstep: none waits
    on the wall clock). ``PYTEST_XDIST_AUTO_NUM_WORKERS`` decides where set."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return int(os.environ["PYTEST_XDIST_AUTO_NUM_WORKERS"])
    return len(os.sched_getaffinity(0)) + EXTRA_WORKERS


#: How much lower the test processes run than the system's own (``nice``): the one bus test that runs in real time
#: on a pseudo-terminal needs the kernel's workers that move a pseudo-terminal's bytes, which the suite's busy
#: processes at the same priority delay by milliseconds (a robot's PC runs no test suite beside its loop).
WORKER_NICE = 10


def pytest_configure(config: pytest.Config) -> None:
    # A suite started in the background of a non-interactive shell (``pytest &``) inherits Ctrl-C ignored, and so
    # would every process it starts: the tests of Ctrl-C need Python's own handler, as in a terminal.
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if os.environ.get("PYTEST_XDIST_WORKER"):
        with contextlib.suppress(OSError):
            os.nice(WORKER_NICE)


_WARMING: list[subprocess.Popen] = []


def pytest_sessionstart(session: pytest.Session) -> None:
    compile_package(ROOT)
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    for copy in (ROOT, warm_kernels.installed_root()):
        if copy is not None and not warm_kernels.cached(copy):
            # a fresh checkout (or install): the kernels compile beside the first tests (which need none), not
            # inside the tests that need them while the other processes wait for the compile's lock
            # (tests/warm_kernels.py)
            _WARMING.append(subprocess.Popen([sys.executable, str(ROOT / "tests" / "warm_kernels.py"), str(copy)],
                                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))


def pytest_sessionfinish(session: pytest.Session) -> None:
    for process in _WARMING:
        process.wait()


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The modules of :data:`LONG_FIRST` first, in their order; every other test keeps its place."""
    def rank(item: pytest.Item) -> int:
        module = item.nodeid.split("::")[0].rsplit("/", 1)[-1]
        return LONG_FIRST.index(module) if module in LONG_FIRST else len(LONG_FIRST)
    items.sort(key=rank)
