"""Shared fixtures: the shipped spec, a seeded RNG, the stock action file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from op2motion.spec import Spec, default_spec

DATA = Path(__file__).parent / "data"
SEED = 20261121


@pytest.fixture(scope="session")
def spec() -> Spec:
    return default_spec()


@pytest.fixture()
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def stock_action_bytes() -> bytes:
    """The stock ROBOTIS motion_4096.bin (copied from shared/reference)."""
    return (DATA / "motion_4096.bin").read_bytes()


def page_last_step_ticks(data: bytes, page: int) -> np.ndarray:
    """Goal ticks of joints 1..20 in the last used step of a page (layout: op2_facts.md §4)."""
    base = page * 512
    steps = data[base + 20]  # stepnum
    step = base + 64 + 64 * (steps - 1)
    words = np.frombuffer(data[step:step + 62], dtype="<u2")
    return words[1:21].astype(int)
