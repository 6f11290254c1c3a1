"""Shared fixtures: the shipped spec, a seeded RNG, the stock action file; op2motion compiled once for the many
subprocesses the tests start (CLI runs, examples, library workers), which would otherwise each compile it again
where Python is told not to write bytecode (PYTHONDONTWRITEBYTECODE)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import ROOT, SEED, STOCK, compile_package

from op2motion.robot.spec import Spec
from op2motion.robot.specfile import default_spec


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


def pytest_sessionstart(session: pytest.Session) -> None:
    compile_package(ROOT)
