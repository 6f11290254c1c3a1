"""Compile op2motion's numba kernels once, in a process of their own, at the start of a test run on a fresh checkout
(``conftest.pytest_sessionstart``): each kernel compiles under its machine-wide lock
(:mod:`op2motion.processes.compiled`), so the test processes that need one later load it from the cache, or wait
for the compile already under way, instead of starting it themselves in the middle of the run while the others idle.
Run as ``python tests/warm_kernels.py [FOLDER]``: the copy of the package in FOLDER (default: this checkout's; a
non-editable install's programs, which the tests start from other folders, run the copy in site-packages, whose
kernels numba caches apart); small problems, the kernels' own argument types."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KERNELS = ("posture/__pycache__/kernel._swarm-*.nbi", "motion/__pycache__/whole_body_kernel._servo_rows-*.nbi")


def installed_root() -> Path | None:
    """The folder holding the installed copy of op2motion, when that is not this checkout's (a non-editable install,
    as the README's quickstart makes); None otherwise."""
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        package = Path(str(distribution("op2motion").locate_file("op2motion")))
    except PackageNotFoundError:
        return None
    if package.is_dir() and package.resolve() != (ROOT / "op2motion").resolve():
        return package.parent
    return None


def cached(root: Path = ROOT) -> bool:
    """Are the kernels of the package at ``root`` in numba's cache already?"""
    return all(any((root / "op2motion").glob(pattern)) for pattern in KERNELS)


def warm() -> None:
    """Call each kernel once on a small problem (the PSO's swarm, the whole-body IK of a short line)."""
    import numpy as np

    from op2motion import book
    from op2motion.formats.posefile import read_pose
    from op2motion.motion.cartesian import LineRequest, line_move
    from op2motion.posture.cost import PostureProblem
    from op2motion.posture.pso import PSOSettings, run_pso
    from op2motion.robot.specfile import default_spec

    spec = default_spec()
    run_pso(PostureProblem.from_scenario(book.DEFAULT_PROBLEM), spec, PSOSettings(particles=8, iterations=2))
    line_move(read_pose(ROOT / "poses" / "walkready.json", spec),
              LineRequest("right", 0.2, delta_m=tuple(np.array([0.0, 0.0, -0.01])), orientation="free", back=False),
              spec)


if __name__ == "__main__":
    sys.path.insert(0, sys.argv[1] if len(sys.argv) > 1 else str(ROOT))
    warm()
